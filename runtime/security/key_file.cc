#include "runtime/security/key_file.h"

#include <fcntl.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <unistd.h>
#include <chrono>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "libs/core/error.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

constexpr size_t kLargestKeyFile = 4096;

// Closes the descriptor however the scope ends.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

std::string Errno() { return std::strerror(errno); }

std::string ModeText(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof(text), "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

}  // namespace

uint32_t KeyIdFromClock() {
  return static_cast<uint32_t>(std::chrono::duration_cast<std::chrono::seconds>(
                                   std::chrono::system_clock::now().time_since_epoch())
                                   .count());
}

AuthKey NewAuthKey(uint32_t id) {
  AuthKey key;
  key.id = id;
  if (RAND_bytes(key.secret.data(), static_cast<int>(key.secret.size())) != 1) {
    throw std::runtime_error("RAND_bytes failed: no key was made");
  }
  return key;
}

void WriteKeyFile(const fs::path& path, const AuthKey& key) {
  const Fd fd(open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600));
  if (fd.get() < 0) {
    throw InputError(path.string() + ": cannot create the key file: " + Errno() +
                     (errno == EEXIST ? " (a key is never overwritten: remove it first)" : ""));
  }
  // The umask cannot widen 0600, but a pre-set ACL default could: set it.
  if (fchmod(fd.get(), 0600) != 0) throw InputError(path.string() + ": chmod 0600: " + Errno());
  const std::string text = FormatKeyText(key);
  if (write(fd.get(), text.data(), text.size()) != static_cast<ssize_t>(text.size()) ||
      fsync(fd.get()) != 0) {
    const std::string error = Errno();
    unlink(path.c_str());
    throw InputError(path.string() + ": cannot write the key file: " + error);
  }
}

AuthKey ReadKeyFile(const fs::path& path) {
  const Fd fd(open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW));
  if (fd.get() < 0) {
    throw InputError(path.string() + ": cannot open the key file: " + Errno());
  }
  struct stat info {};
  if (fstat(fd.get(), &info) != 0) throw InputError(path.string() + ": " + Errno());
  if (!S_ISREG(info.st_mode)) throw InputError(path.string() + ": not a regular file");
  if ((info.st_mode & 077) != 0) {
    throw InputError(path.string() +
                     ": a key file must be readable by its owner only, its mode is " +
                     ModeText(info.st_mode) + " (chmod 600 " + path.string() + ")");
  }
  if (info.st_size > static_cast<off_t>(kLargestKeyFile)) {
    throw InputError(path.string() + ": too large for a key file");
  }
  std::string text(static_cast<size_t>(info.st_size), '\0');
  if (read(fd.get(), text.data(), text.size()) != static_cast<ssize_t>(text.size())) {
    throw InputError(path.string() + ": cannot read the key file: " + Errno());
  }
  return ParseKeyText(text, path.string());
}

KeyRing ReadKeyRing(const std::vector<fs::path>& paths) {
  std::vector<AuthKey> keys;
  keys.reserve(paths.size());
  for (const fs::path& path : paths) keys.push_back(ReadKeyFile(path));
  return KeyRing(std::move(keys));
}

}  // namespace shapesense
