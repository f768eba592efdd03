#pragma once

// A rig key in a file of its own (mode 0600, as `shapesense keygen` writes
// it), removed with the object.
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>

#include "runtime/security/key_file.h"

namespace shapesense::test_keys {

class TemporaryKeyFile {
 public:
  explicit TemporaryKeyFile(uint32_t id = 1, const AuthKey* key = nullptr)
      : dir_(std::filesystem::temp_directory_path() /
             ("shapesense_key_" + std::to_string(getpid()) + "_" + std::to_string(next_++))) {
    std::filesystem::create_directories(dir_);
    path_ = dir_ / "rig.key";
    WriteKeyFile(path_, key != nullptr ? *key : NewAuthKey(id));
  }
  ~TemporaryKeyFile() {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  TemporaryKeyFile(const TemporaryKeyFile&) = delete;
  TemporaryKeyFile& operator=(const TemporaryKeyFile&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  static inline std::atomic<int> next_{0};
  std::filesystem::path dir_;
  std::filesystem::path path_;
};

}  // namespace shapesense::test_keys
