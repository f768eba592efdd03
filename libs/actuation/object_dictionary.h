#pragma once

// A CANopen object dictionary for the simulated drive: entries of 1, 2 or 4
// bytes with their access, range and defaults, read and written as an SDO
// server does (with CiA 301 abort codes) or directly by the device itself.

#include <cstdint>
#include <map>
#include <vector>

namespace shapesense {

struct OdEntry {
  enum class Access { kReadOnly, kReadWrite };
  uint8_t size = 4;  // bytes: 1, 2 or 4
  bool is_signed = false;
  Access access = Access::kReadWrite;
  uint32_t default_value = 0;
  int64_t min = 0;  // a written value outside [min, max] is refused
  int64_t max = 0xFFFFFFFF;
  std::vector<int64_t> allowed;  // when not empty: the only values a write may give
  bool mappable = false;         // may be mapped into a PDO
  uint32_t value = 0;
};

class ObjectDictionary {
 public:
  // Adds an entry holding its default value.
  void Add(uint16_t index, uint8_t subindex, OdEntry entry);
  const OdEntry* Find(uint16_t index, uint8_t subindex) const;

  // As an SDO server: 0, or the abort code (no object, write-only, ...).
  uint32_t Read(uint16_t index, uint8_t subindex, uint32_t* value, uint8_t* size) const;
  // As an SDO server: access, length (`size` 0: not given) and range checks;
  // 0 or the abort code.
  uint32_t Write(uint16_t index, uint8_t subindex, uint32_t value, uint8_t size);

  // The device's own access, unchecked (the entry must exist).
  uint32_t Get(uint16_t index, uint8_t subindex) const;
  int32_t GetSigned(uint16_t index, uint8_t subindex) const;
  void Set(uint16_t index, uint8_t subindex, uint32_t value);

  // Every entry with first_index <= index <= last_index back to its default.
  void ResetRange(uint16_t first_index, uint16_t last_index);

 private:
  static uint32_t Key(uint16_t index, uint8_t subindex) {
    return (static_cast<uint32_t>(index) << 8) | subindex;
  }
  uint32_t CheckValue(const OdEntry& entry, uint32_t value) const;

  std::map<uint32_t, OdEntry> entries_;
};

}  // namespace shapesense
