#include "base/sha256.h"

#include <openssl/err.h>
#include <openssl/evp.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "base/errors.h"

namespace fetchscope {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

[[noreturn]] void ThrowOpenSsl(const char* what) {
  char detail[256] = "no detail";
  if (const unsigned long code = ERR_get_error()) ERR_error_string_n(code, detail, sizeof(detail));
  throw RunError(std::string("SHA-256 (OpenSSL libcrypto): ") + what + " failed: " + detail);
}

}  // namespace

void Sha256::CtxFree::operator()(evp_md_ctx_st* ctx) const { EVP_MD_CTX_free(ctx); }

Sha256::Sha256() : ctx_(EVP_MD_CTX_new()) {
  if (!ctx_) ThrowOpenSsl("EVP_MD_CTX_new");
  if (EVP_DigestInit_ex(ctx_.get(), EVP_sha256(), nullptr) != 1) ThrowOpenSsl("EVP_DigestInit_ex");
}

Sha256::~Sha256() = default;
Sha256::Sha256(Sha256&&) noexcept = default;
Sha256& Sha256::operator=(Sha256&&) noexcept = default;

void Sha256::Update(const void* data, size_t size) {
  if (size == 0) return;
  if (EVP_DigestUpdate(ctx_.get(), data, size) != 1) ThrowOpenSsl("EVP_DigestUpdate");
}

std::string Sha256::HexDigest() {
  if (!digest_.empty()) return digest_;
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(ctx_.get(), digest, &length) != 1) ThrowOpenSsl("EVP_DigestFinal_ex");
  static const char kHex[] = "0123456789abcdef";
  digest_.reserve(2 * length);
  for (unsigned int i = 0; i < length; ++i) {
    digest_.push_back(kHex[digest[i] >> 4]);
    digest_.push_back(kHex[digest[i] & 0xf]);
  }
  return digest_;
}

std::string Sha256Hex(const std::string& bytes) {
  Sha256 hash;
  hash.Update(bytes.data(), bytes.size());
  return hash.HexDigest();
}

std::string Sha256OfFile(const std::filesystem::path& path) {
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) {
    throw RunError("cannot read '" + path.string() + "': " + std::strerror(errno));
  }
  Sha256 hash;
  std::array<char, 1 << 16> buffer;
  size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), file.get())) > 0) {
    hash.Update(buffer.data(), n);
  }
  if (std::ferror(file.get())) {
    throw RunError("reading '" + path.string() + "' failed: " + std::strerror(errno));
  }
  return hash.HexDigest();
}

std::string Sha256OfTree(const std::filesystem::path& root,
                         const std::vector<std::string>& subdirs) {
  namespace fs = std::filesystem;
  std::vector<std::string> records;
  for (const std::string& subdir : subdirs) {
    const fs::path folder = root / subdir;
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) continue;
    fs::recursive_directory_iterator it(folder, ec), end;
    if (ec) throw RunError("cannot list '" + folder.string() + "': " + ec.message());
    for (; it != end; it.increment(ec)) {
      if (ec) throw RunError("cannot list '" + folder.string() + "': " + ec.message());
      if (!it->is_regular_file()) continue;
      // normal form: the subfolder "." or a root ending in '/' give the same names
      const std::string relative =
          it->path().lexically_relative(root).lexically_normal().generic_string();
      records.push_back(relative + '\0' + Sha256OfFile(it->path()) + '\n');
    }
    if (ec) throw RunError("cannot list '" + folder.string() + "': " + ec.message());
  }
  std::sort(records.begin(), records.end());
  Sha256 hash;
  for (const std::string& record : records) hash.Update(record.data(), record.size());
  return hash.HexDigest();
}

}  // namespace fetchscope
