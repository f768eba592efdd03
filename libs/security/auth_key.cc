#include "libs/security/auth_key.h"

#include <algorithm>
#include <charconv>
#include <sstream>

#include "libs/core/error.h"

namespace shapesense {
namespace {

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string Trimmed(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(" \t\r") - begin + 1);
}

std::array<uint8_t, kAuthKeyBytes> ParseSecret(const std::string& hex, const std::string& source) {
  std::array<uint8_t, kAuthKeyBytes> secret{};
  if (hex.size() != 2 * kAuthKeyBytes) {
    throw InputError(source + ": secret: expected " + std::to_string(2 * kAuthKeyBytes) +
                     " hex digits (a 256-bit key)");
  }
  for (size_t i = 0; i < kAuthKeyBytes; ++i) {
    const int high = HexDigit(hex[2 * i]);
    const int low = HexDigit(hex[2 * i + 1]);
    if (high < 0 || low < 0) throw InputError(source + ": secret: not hex digits");
    secret[i] = static_cast<uint8_t>(high * 16 + low);
  }
  return secret;
}

uint32_t ParseId(const std::string& text, const std::string& source) {
  uint32_t id = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), id);
  if (error != std::errc() || end != text.data() + text.size()) {
    throw InputError(source + ": key_id: expected a whole number 0-4294967295, got '" + text + "'");
  }
  return id;
}

}  // namespace

AuthKey ParseKeyText(const std::string& text, const std::string& source) {
  std::optional<uint32_t> id;
  std::optional<std::array<uint8_t, kAuthKeyBytes>> secret;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    line = Trimmed(line);
    if (line.empty() || line.front() == '#') continue;
    const size_t colon = line.find(':');
    const std::string key = colon == std::string::npos ? line : Trimmed(line.substr(0, colon));
    const std::string value = colon == std::string::npos ? "" : Trimmed(line.substr(colon + 1));
    if (key == "key_id") {
      id = ParseId(value, source);
    } else if (key == "secret") {
      secret = ParseSecret(value, source);
    } else {
      // Only the part before the colon: a mangled secret line stays unshown.
      std::string message = source;
      message += ": unknown key '" + key + "' (expected key_id and secret)";
      throw InputError(message);
    }
  }
  if (!id) throw InputError(source + ": no key_id");
  if (!secret) throw InputError(source + ": no secret");
  return {*id, *secret};
}

std::string FormatKeyText(const AuthKey& key) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (const uint8_t byte : key.secret) {
    hex += kHex[byte >> 4];
    hex += kHex[byte & 15];
  }
  return "# shapesense message key (docs/security.md): keep this file mode 0600 and on the\n"
         "# rig's hosts only; `shapesense keygen` makes a new one.\n"
         "key_id: " +
         std::to_string(key.id) + "\nsecret: " + hex + "\n";
}

KeyRing::KeyRing(std::vector<AuthKey> keys) : keys_(std::move(keys)) {
  if (keys_.empty()) throw InputError("key ring: no key");
  if (keys_.size() > kMaxKeys) {
    throw InputError("key ring: " + std::to_string(keys_.size()) + " keys, at most " +
                     std::to_string(kMaxKeys) + " (the current one and the one it replaces)");
  }
  for (size_t i = 0; i < keys_.size(); ++i) {
    for (size_t j = i + 1; j < keys_.size(); ++j) {
      if (keys_[i].id == keys_[j].id) {
        throw InputError("key ring: two keys with id " + std::to_string(keys_[i].id));
      }
    }
  }
}

const AuthKey* KeyRing::Find(uint32_t id) const {
  const auto found =
      std::find_if(keys_.begin(), keys_.end(), [id](const AuthKey& key) { return key.id == id; });
  return found == keys_.end() ? nullptr : &*found;
}

std::vector<uint32_t> KeyRing::ids() const {
  std::vector<uint32_t> ids;
  ids.reserve(keys_.size());
  for (const AuthKey& key : keys_) ids.push_back(key.id);
  return ids;
}

}  // namespace shapesense
