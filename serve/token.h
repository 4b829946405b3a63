// serve's access token (Jupyter's model): a random token of 192 bits on the first URL, exchanged
// for a cookie; every request carries one of them and is checked in constant time.
#pragma once

#include <string>

namespace fetchscope::serve {

/// Bits of a token NewToken makes.
inline constexpr int kTokenBits = 192;
/// The shortest token a --token-file may hold (128 bits as hex).
inline constexpr size_t kMinTokenLength = 32;

/// A new random token: kTokenBits from the kernel's generator (getrandom), as lowercase hex.
/// Throws RunError when the kernel gives none.
std::string NewToken();

/// Whether `given` equals `token`, in time that depends on their lengths only (CRYPTO_memcmp).
bool SameToken(const std::string& given, const std::string& token);

/// --token-file: the token `path` holds (its first line), or, where there is no such file, a new
/// one written there (mode 0600, atomically) for scripts to read. Throws UsageError for a token
/// shorter than kMinTokenLength or with characters other than letters, digits and "-._~", and
/// RunError when the file cannot be read or written.
std::string TokenFromFile(const std::string& path);

}  // namespace fetchscope::serve
