// MD5 digests of shards and files (index.json's md5sum), through OpenSSL's libcrypto.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

struct evp_md_ctx_st;  // OpenSSL (openssl/evp.h), kept out of this header

namespace gt::io {

// Lower-case hex MD5 of bytes / of a file.
std::string Md5Hex(std::string_view bytes);
// The same, incrementally: Update any number of times, then HexDigest once.
// OpenSSL's MD5 (libcrypto, ~1.3x the speed of the RFC 1321 code occgt had; a shard's
// digest is computed in the serial stage of the write pipeline). Movable, not copyable.
class Md5 {
 public:
  Md5();
  ~Md5();
  Md5(Md5&&) noexcept;
  Md5& operator=(Md5&&) noexcept;
  Md5(const Md5&) = delete;
  Md5& operator=(const Md5&) = delete;
  void Update(const void* data, size_t n);
  std::string HexDigest();

 private:
  evp_md_ctx_st* ctx_ = nullptr;  // OpenSSL's EVP_MD_CTX
};
std::string Md5HexOfFile(const std::string& path);

}  // namespace gt::io
