#include "libgt/io/md5.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>

#include <fstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "libgt/core/error.h"

namespace gt::io {

// MD5 through OpenSSL's EVP interface.
namespace {
// OpenSSL's MD5 implementation, fetched once for the process (EVP_md5() is fetched again at
// every digest's start). The machine's openssl.cnf is not loaded: a digest must not depend
// on it, and reading it (~0.5 ms, more when the file has left the page cache) was on the
// serial start of every build.
const EVP_MD* Md5Method() {
  static const EVP_MD* const md = [] {
    OPENSSL_init_crypto(OPENSSL_INIT_NO_LOAD_CONFIG, nullptr);
    return EVP_MD_fetch(nullptr, "MD5", nullptr);
  }();
  return md;
}
}  // namespace

Md5::Md5() : ctx_(EVP_MD_CTX_new()) {
  const EVP_MD* md = Md5Method();
  if (ctx_ == nullptr || md == nullptr || EVP_DigestInit_ex(ctx_, md, nullptr) != 1) {
    throw std::runtime_error("OpenSSL: cannot start an MD5 digest");
  }
}
Md5::~Md5() { EVP_MD_CTX_free(ctx_); }
Md5::Md5(Md5&& other) noexcept : ctx_(other.ctx_) { other.ctx_ = nullptr; }
Md5& Md5::operator=(Md5&& other) noexcept {
  std::swap(ctx_, other.ctx_);
  return *this;
}

void Md5::Update(const void* data, size_t n) {
  if (n > 0 && EVP_DigestUpdate(ctx_, data, n) != 1) {
    throw std::runtime_error("OpenSSL: MD5 update failed");
  }
}

std::string Md5::HexDigest() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(ctx_, digest, &length) != 1 || length != 16) {
    throw std::runtime_error("OpenSSL: MD5 final failed");
  }
  static const char* kHex = "0123456789abcdef";
  std::string out;
  out.reserve(32);
  for (unsigned int i = 0; i < length; ++i) {
    out.push_back(kHex[digest[i] >> 4]);
    out.push_back(kHex[digest[i] & 15]);
  }
  return out;
}

std::string Md5Hex(std::string_view bytes) {
  Md5 md5;
  md5.Update(bytes.data(), bytes.size());
  return md5.HexDigest();
}

std::string Md5HexOfFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  Md5 md5;
  std::vector<char> buf(1 << 16);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    const std::streamsize n = in.gcount();
    if (n > 0) md5.Update(buf.data(), static_cast<size_t>(n));
  }
  if (in.bad()) throw InputError(path, "read error");
  return md5.HexDigest();
}

}  // namespace gt::io
