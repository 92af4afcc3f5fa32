#include "wall/service/security/Credentials.h"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "base/Error.h"
#include "wall/service/security/WallToken.h"

namespace wall::service {
namespace {

constexpr const char* kPublicFile = "wall-public.key";
constexpr const char* kSecretFile = "wall-secret.key";
constexpr std::size_t kKeyBytes = 32, kZ85Chars = 40;
// ZMQ_ZAP_DOMAIN of our servers: a request for any other is not ours.
constexpr const char* kDomain = "dfbwall";

void startSodium() {
  if (sodium_init() < 0) throw base::Error("libsodium failed to start");
}

// One key of Z85 text from `path`; `what` names it in errors.
std::string readKey(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  std::string line;
  if (!in || !std::getline(in, line))
    throw base::Error(what + ": cannot read it" +
                      (std::filesystem::exists(path) ? ""
                                                     : " (no such file; dfbwall keygen DIR "
                                                       "writes a key pair)"));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  std::uint8_t key[kKeyBytes];
  if (line.size() != kZ85Chars || !zmq_z85_decode(key, line.c_str()))
    throw base::Error(what +
                      ": not a key (expected one line of 40 Z85 characters, as "
                      "dfbwall keygen writes)");
  return std::string(reinterpret_cast<const char*>(key), kKeyBytes);
}

void writeFile(const std::string& path, const std::string& text, mode_t mode) {
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0)
    throw base::Error(path + ": cannot create it (" + std::strerror(errno) +
                      (errno == EEXIST ? "; keygen never overwrites a key" : "") + ")");
  const bool written = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  fchmod(fd, mode);
  close(fd);
  if (!written) throw base::Error(path + ": cannot write it");
}

}  // namespace

Credentials loadCredentials(const CredentialOptions& o, bool createToken) {
  Credentials c;
  const WallToken token = chooseWallToken(o.token, o.tokenFile, createToken);
  c.token = token.token;
  c.tokenSource = token.source;
  if (!o.curveDir.empty()) {
    const KeyPair pair = readKeyPair(o.curveDir, "--curve");
    c.publicKey = pair.publicKey;
    c.secretKey = pair.secretKey;
    c.serverKey = pair.publicKey;
  }
  if (!o.serverKeyFile.empty()) c.serverKey = readPublicKey(o.serverKeyFile, "--server-key");
  return c;
}

void makeServer(zmq::socket_t& socket, const Credentials& c) {
  socket.set(zmq::sockopt::zap_domain, kDomain);
  if (c.secretKey.empty()) {
    socket.set(zmq::sockopt::plain_server, 1);
    return;
  }
  socket.set(zmq::sockopt::curve_server, 1);
  socket.set(zmq::sockopt::curve_secretkey, zmq::buffer(c.secretKey.data(), c.secretKey.size()));
}

void makeClient(zmq::socket_t& socket, const Credentials& c) {
  if (c.serverKey.empty()) {
    socket.set(zmq::sockopt::plain_username, "dfbwall");
    socket.set(zmq::sockopt::plain_password, c.token);
    return;
  }
  const KeyPair mine = clientKeys(c.token);
  socket.set(zmq::sockopt::curve_serverkey, zmq::buffer(c.serverKey.data(), c.serverKey.size()));
  socket.set(zmq::sockopt::curve_publickey, zmq::buffer(mine.publicKey.data(), kKeyBytes));
  socket.set(zmq::sockopt::curve_secretkey, zmq::buffer(mine.secretKey.data(), kKeyBytes));
}

KeyPair clientKeys(const std::string& token) {
  startSodium();
  // The seed is a keyed hash of the token: the public key tells nothing about it, and a key
  // pair derived for anything else never matches.
  static const char kContext[] = "dfbwall wall-service client key";
  unsigned char seed[crypto_box_SEEDBYTES];
  crypto_generichash(seed, sizeof seed, reinterpret_cast<const unsigned char*>(token.data()),
                     token.size(), reinterpret_cast<const unsigned char*>(kContext),
                     sizeof kContext - 1);
  unsigned char pk[crypto_box_PUBLICKEYBYTES], sk[crypto_box_SECRETKEYBYTES];
  crypto_box_seed_keypair(pk, sk, seed);
  sodium_memzero(seed, sizeof seed);
  KeyPair pair{std::string(reinterpret_cast<const char*>(pk), sizeof pk),
               std::string(reinterpret_cast<const char*>(sk), sizeof sk)};
  sodium_memzero(sk, sizeof sk);
  return pair;
}

bool sameSecret(const std::string& a, const std::string& b) {
  startSodium();
  // Hashes of equal length, compared in constant time: neither the content nor the length of
  // the secret shows in the time taken.
  unsigned char ha[32], hb[32];
  crypto_generichash(ha, sizeof ha, reinterpret_cast<const unsigned char*>(a.data()), a.size(),
                     nullptr, 0);
  crypto_generichash(hb, sizeof hb, reinterpret_cast<const unsigned char*>(b.data()), b.size(),
                     nullptr, 0);
  return sodium_memcmp(ha, hb, sizeof ha) == 0;
}

std::string writeKeyPair(const std::string& dir) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw base::Error(dir + ": cannot create it (" + error.message() + ")");
  char publicText[kZ85Chars + 1], secretText[kZ85Chars + 1];
  if (zmq_curve_keypair(publicText, secretText) != 0)
    throw base::Error("this ZeroMQ has no CURVE (libzmq built without libsodium)");
  const std::string publicPath = (std::filesystem::path(dir) / kPublicFile).string();
  const std::string secretPath = (std::filesystem::path(dir) / kSecretFile).string();
  if (std::filesystem::exists(publicPath) || std::filesystem::exists(secretPath))
    throw base::Error(dir +
                      ": holds a key pair already; keygen never overwrites a key (use a "
                      "new folder, then replace the old one)");
  writeFile(secretPath, std::string(secretText) + "\n", 0600);
  writeFile(publicPath, std::string(publicText) + "\n", 0644);
  sodium_memzero(secretText, sizeof secretText);
  return publicPath;
}

KeyPair readKeyPair(const std::string& dir, const std::string& option) {
  const std::string secretPath = (std::filesystem::path(dir) / kSecretFile).string();
  struct stat st {};
  if (stat(secretPath.c_str(), &st) == 0 && (st.st_mode & 077) != 0)
    throw base::Error(option + " " + dir + ": " + secretPath +
                      " may be read by other users; make it private (chmod 600 " + secretPath +
                      ")");
  KeyPair pair;
  pair.secretKey = readKey(secretPath, option + " " + dir + ": " + secretPath);
  pair.publicKey =
      readPublicKey((std::filesystem::path(dir) / kPublicFile).string(), option + " " + dir + ":");
  // The public key must be the secret one's: a mismatch would lock every client out.
  startSodium();
  unsigned char derived[crypto_scalarmult_BYTES];
  crypto_scalarmult_base(derived, reinterpret_cast<const unsigned char*>(pair.secretKey.data()));
  if (std::memcmp(derived, pair.publicKey.data(), kKeyBytes) != 0)
    throw base::Error(option + " " + dir + ": " + kPublicFile + " is not the public key of " +
                      kSecretFile);
  return pair;
}

std::string readPublicKey(const std::string& file, const std::string& option) {
  return readKey(file, option + " " + file);
}

}  // namespace wall::service
