#pragma once

// Key files on disk (docs/security.md): written 0600 and never over another
// file, read only when neither group nor others can read them. Errors name
// the file and what is wrong, never the secret.
#include <cstdint>
#include <filesystem>
#include <vector>

#include "libs/security/auth_key.h"

namespace shapesense {

// A key id from the clock, in seconds: a newer key has a larger id.
uint32_t KeyIdFromClock();

// A new key with a secret from OpenSSL's RAND_bytes (the kernel's entropy).
// Throws std::runtime_error when the generator fails.
AuthKey NewAuthKey(uint32_t id);

// Writes `key` to a new file of mode 0600; InputError when the file exists
// (a key is never overwritten) or cannot be written.
void WriteKeyFile(const std::filesystem::path& path, const AuthKey& key);

// Reads a key file; InputError when it is missing, not a regular file,
// readable by group or others, or malformed.
AuthKey ReadKeyFile(const std::filesystem::path& path);

// The ring of one or two key files (the second: the key being rotated in,
// which signs). InputError as ReadKeyFile, or for a bad ring.
KeyRing ReadKeyRing(const std::vector<std::filesystem::path>& paths);

}  // namespace shapesense
