#include "libs/security/hmac.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>

#include <memory>
#include <stdexcept>

namespace shapesense {
namespace {

struct MacDeleter {
  void operator()(EVP_MAC* mac) const { EVP_MAC_free(mac); }
  void operator()(EVP_MAC_CTX* context) const { EVP_MAC_CTX_free(context); }
};

void Check(int ok, const char* what) {
  if (ok != 1) throw std::runtime_error(std::string("libcrypto: ") + what + " failed");
}

}  // namespace

Mac HmacSha256(std::span<const uint8_t> key, std::span<const std::span<const uint8_t>> parts) {
  // The algorithm is fetched once; a context per call keeps this thread-safe.
  static const std::unique_ptr<EVP_MAC, MacDeleter> algorithm(
      EVP_MAC_fetch(nullptr, "HMAC", nullptr));
  if (!algorithm) throw std::runtime_error("libcrypto: no HMAC");
  const std::unique_ptr<EVP_MAC_CTX, MacDeleter> context(EVP_MAC_CTX_new(algorithm.get()));
  if (!context) throw std::runtime_error("libcrypto: EVP_MAC_CTX_new failed");
  char digest[] = "SHA256";
  const OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string("digest", digest, 0),
                               OSSL_PARAM_construct_end()};
  Check(EVP_MAC_init(context.get(), key.data(), key.size(), params), "EVP_MAC_init");
  for (const std::span<const uint8_t> part : parts) {
    Check(EVP_MAC_update(context.get(), part.data(), part.size()), "EVP_MAC_update");
  }
  Mac mac{};
  size_t length = 0;
  Check(EVP_MAC_final(context.get(), mac.data(), &length, mac.size()), "EVP_MAC_final");
  if (length != mac.size()) throw std::runtime_error("libcrypto: HMAC-SHA256 of an odd length");
  return mac;
}

bool MacsEqual(std::span<const uint8_t> a, std::span<const uint8_t> b) {
  return a.size() == b.size() && CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

}  // namespace shapesense
