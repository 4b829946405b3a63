#include "serve/token.h"

#include <openssl/crypto.h>
#include <sys/random.h>
#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>

#include "base/atomic_file.h"
#include "base/errors.h"

namespace fetchscope::serve {

std::string NewToken() {
  unsigned char bytes[kTokenBits / 8];
  size_t got = 0;
  while (got < sizeof(bytes)) {
    const ssize_t n = getrandom(bytes + got, sizeof(bytes) - got, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw RunError(std::string("cannot make a token: getrandom: ") + strerror(errno));
    got += static_cast<size_t>(n);
  }
  static const char kHex[] = "0123456789abcdef";
  std::string token;
  for (unsigned char b : bytes) {
    token += kHex[b >> 4];
    token += kHex[b & 15];
  }
  return token;
}

bool SameToken(const std::string& given, const std::string& token) {
  return given.size() == token.size() && !token.empty() &&
         CRYPTO_memcmp(given.data(), token.data(), token.size()) == 0;
}

std::string TokenFromFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    struct stat st;
    if (stat(path.c_str(), &st) == 0) {
      throw RunError("--token-file " + path + ": cannot be read: " + strerror(errno));
    }
    const std::string token = NewToken();
    AtomicFile file(path);
    fchmod(fileno(file.file()), 0600);  // before the token is in it: for the user alone
    file.Write(token + "\n");
    file.Commit();
    return token;
  }
  std::string token;
  std::getline(in, token);
  while (!token.empty() && (token.back() == '\r' || token.back() == ' ')) token.pop_back();
  for (char c : token) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && !std::strchr("-._~", c)) {
      throw UsageError("--token-file " + path +
                       ": the token has a character other than letters, digits and -._~");
    }
  }
  if (token.size() < kMinTokenLength) {
    throw UsageError("--token-file " + path + ": a token of " + std::to_string(token.size()) +
                     " characters is too short; accepted: at least " +
                     std::to_string(kMinTokenLength) + " (128 bits as hex)");
  }
  return token;
}

}  // namespace fetchscope::serve
