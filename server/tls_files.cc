#include "server/tls_files.h"

#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <memory>

#include "absl/strings/str_cat.h"

namespace tetrefine::server {
namespace {

struct BioFree {
  void operator()(BIO* bio) const { BIO_free(bio); }
};
struct X509Free {
  void operator()(X509* x) const { X509_free(x); }
};
struct KeyFree {
  void operator()(EVP_PKEY* key) const { EVP_PKEY_free(key); }
};

std::unique_ptr<BIO, BioFree> Reader(const std::string& pem) {
  return std::unique_ptr<BIO, BioFree>(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())));
}

// The first certificate of a PEM text, or null.
std::unique_ptr<X509, X509Free> FirstCertificate(const std::string& pem) {
  auto bio = Reader(pem);
  return std::unique_ptr<X509, X509Free>(
      bio ? PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr) : nullptr);
}

absl::Status NoCertificate(const char* flag, const std::string& path) {
  return absl::InvalidArgumentError(
      absl::StrCat(flag, ": ", path, " holds no PEM certificate (-----BEGIN CERTIFICATE-----)"));
}

}  // namespace

absl::Status CheckTlsFiles(const PemFile& cert_file, const PemFile& key_file,
                           const PemFile& ca_file) {
  if (!cert_file.path.empty()) {
    std::unique_ptr<X509, X509Free> cert = FirstCertificate(cert_file.pem);
    if (cert == nullptr) return NoCertificate(cert_file.flag.c_str(), cert_file.path);
    auto bio = Reader(key_file.pem);
    std::unique_ptr<EVP_PKEY, KeyFree> key(
        bio ? PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr) : nullptr);
    if (key == nullptr) {
      return absl::InvalidArgumentError(
          absl::StrCat(key_file.flag, ": ", key_file.path,
                       " holds no unencrypted PEM private key (-----BEGIN PRIVATE KEY-----)"));
    }
    if (X509_check_private_key(cert.get(), key.get()) != 1) {
      return absl::InvalidArgumentError(
          absl::StrCat(key_file.flag, ": ", key_file.path, " is not the private key of the ",
                       cert_file.flag, " certificate in ", cert_file.path));
    }
  }
  if (!ca_file.path.empty() && FirstCertificate(ca_file.pem) == nullptr) {
    return NoCertificate(ca_file.flag.c_str(), ca_file.path);
  }
  return absl::OkStatus();
}

absl::Status CheckServerTlsFiles(const std::string& cert_pem, const std::string& cert_path,
                                 const std::string& key_pem, const std::string& key_path,
                                 const std::string& ca_pem, const std::string& ca_path) {
  return CheckTlsFiles({cert_pem, cert_path, "--tls_cert"}, {key_pem, key_path, "--tls_key"},
                       {ca_pem, ca_path, "--tls_client_ca"});
}

}  // namespace tetrefine::server
