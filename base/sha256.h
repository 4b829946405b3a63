// SHA-256 (FIPS 180-4) through OpenSSL's libcrypto EVP interface, used to record which assets an
// output was made with.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

struct evp_md_ctx_st;  // OpenSSL's EVP_MD_CTX, kept out of this header

namespace fetchscope {

/// Incremental SHA-256: Update() any number of times, then HexDigest() once.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(Sha256&&) noexcept;
  Sha256& operator=(Sha256&&) noexcept;
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  /// Feeds `size` more bytes of the message.
  void Update(const void* data, size_t size);

  /// Finishes the hash and returns 64 lowercase hex digits. Further Update() calls are not
  /// allowed; further HexDigest() calls return the same digest.
  std::string HexDigest();

 private:
  struct CtxFree {
    void operator()(evp_md_ctx_st* ctx) const;
  };
  std::unique_ptr<evp_md_ctx_st, CtxFree> ctx_;
  std::string digest_;  // set once finished
};

/// SHA-256 of `bytes` as 64 lowercase hex digits.
std::string Sha256Hex(const std::string& bytes);

/// SHA-256 of a file's contents as 64 lowercase hex digits. Throws RunError if it cannot be read.
std::string Sha256OfFile(const std::filesystem::path& path);

/// A content hash of a folder tree, independent of timestamps and traversal order.
///
/// For each name in `subdirs` whose folder root/name exists, every regular file under it
/// (recursively; a symlink to a file counts as that file, symlinked folders are not entered)
/// contributes one record
///     <path relative to root, '/'-separated> '\0' <sha256 hex of the file's bytes> '\n'
/// The records are sorted bytewise and concatenated, and the result is the SHA-256 hex of that
/// concatenation. Missing subfolders contribute nothing (so the hash of an empty selection is
/// Sha256Hex("")). Throws RunError if a file cannot be read.
std::string Sha256OfTree(const std::filesystem::path& root,
                         const std::vector<std::string>& subdirs);

}  // namespace fetchscope
