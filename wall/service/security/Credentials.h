#pragma once
// How the wall service's sockets authenticate (docs/security.md, "The wall service"). ZeroMQ
// does it at the handshake, before any message reaches our code: every socket a wall process or
// relay binds is a server whose ZAP handler (wall/service/security/Gatekeeper.h) admits only a
// peer that holds the wall's token; every socket that connects to one is a client presenting it.
//
//  - Without CURVE: the PLAIN mechanism, the token as the password (in clear on the wire: for
//    one host, or a network nobody else can read).
//  - With CURVE (`serve --curve DIR`, a key pair from `dfbwall keygen`): everything is
//    encrypted; clients pin the wall's public key (`--server-key FILE`), so a host without its
//    secret key cannot pose as the wall; and a client's own key pair is derived from the token,
//    so the gatekeeper admits exactly that public key and the token never crosses the wire.
#include <zmq.hpp>

#include <string>

namespace wall::service {

struct Credentials {
  std::string token;        // what every peer of the wall holds
  std::string tokenSource;  // where it came from, for messages (never the token itself)
  // Serving with CURVE: this process's key pair (32 bytes each); empty: PLAIN.
  std::string publicKey, secretKey;
  // Connecting with CURVE: the public key the wall (or relay) must hold; empty: PLAIN.
  std::string serverKey;
};

struct KeyPair {
  std::string publicKey, secretKey;  // 32 bytes each
};

// Where a command's credentials come from: its options (empty: not given).
struct CredentialOptions {
  std::string token, tokenFile;  // --token, --token-file (wall/service/security/WallToken.h)
  std::string curveDir;          // serve/relay --curve DIR: serve with this key pair
  std::string serverKeyFile;     // --server-key FILE: connect with CURVE, pinning this key
};
// The token (created when `createToken` and its file is absent), the key pair of curveDir and
// the pinned key (serverKeyFile, else curveDir's own public key). Throws base::Error naming the
// option and file.
Credentials loadCredentials(const CredentialOptions& options, bool createToken);

// Before bind: a PLAIN or CURVE server (a Gatekeeper must run in the socket's context).
void makeServer(zmq::socket_t& socket, const Credentials& credentials);
// Before connect: a PLAIN client presenting the token, or a CURVE client with the token's key
// pair that accepts only credentials.serverKey.
void makeClient(zmq::socket_t& socket, const Credentials& credentials);

// The CURVE key pair every client of a wall with this token uses.
KeyPair clientKeys(const std::string& token);
// Whether two secrets are equal, in time that does not depend on where they differ.
bool sameSecret(const std::string& a, const std::string& b);

// `dfbwall keygen DIR`: a new key pair, DIR/wall-public.key (mode 0644) and DIR/wall-secret.key
// (0600), each one line of Z85 text. Refuses to overwrite either. Returns the public key's path.
std::string writeKeyPair(const std::string& dir);
// The key pair of `dir` (serve --curve DIR). Throws base::Error naming `option` and the file.
KeyPair readKeyPair(const std::string& dir, const std::string& option);
// A public key file (--server-key FILE; also DIR/wall-public.key). Throws base::Error naming
// `option` and the file.
std::string readPublicKey(const std::string& file, const std::string& option);

}  // namespace wall::service
