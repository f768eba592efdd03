#include "libs/actuation/object_dictionary.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "libs/actuation/canopen.h"

namespace shapesense {

void ObjectDictionary::Add(uint16_t index, uint8_t subindex, OdEntry entry) {
  entry.value = entry.default_value;
  entries_[Key(index, subindex)] = std::move(entry);
}

const OdEntry* ObjectDictionary::Find(uint16_t index, uint8_t subindex) const {
  const auto it = entries_.find(Key(index, subindex));
  return it == entries_.end() ? nullptr : &it->second;
}

uint32_t ObjectDictionary::Read(uint16_t index, uint8_t subindex, uint32_t* value,
                                uint8_t* size) const {
  const OdEntry* entry = Find(index, subindex);
  if (!entry) {
    const auto first = entries_.lower_bound(Key(index, 0));
    const bool index_exists = first != entries_.end() && first->first >> 8 == index;
    return index_exists ? canopen::sdo_abort::kNoSubindex : canopen::sdo_abort::kNoObject;
  }
  *value = entry->value;
  *size = entry->size;
  return 0;
}

uint32_t ObjectDictionary::CheckValue(const OdEntry& entry, uint32_t value) const {
  const int64_t number =
      entry.is_signed ? canopen::SignExtend(value, entry.size) : static_cast<int64_t>(value);
  if (!entry.allowed.empty() &&
      std::find(entry.allowed.begin(), entry.allowed.end(), number) == entry.allowed.end()) {
    return canopen::sdo_abort::kInvalidValue;
  }
  if (number > entry.max) return canopen::sdo_abort::kValueTooHigh;
  if (number < entry.min) return canopen::sdo_abort::kValueTooLow;
  return 0;
}

uint32_t ObjectDictionary::Write(uint16_t index, uint8_t subindex, uint32_t value, uint8_t size) {
  uint32_t unused_value = 0;
  uint8_t unused_size = 0;
  if (const uint32_t abort = Read(index, subindex, &unused_value, &unused_size); abort != 0) {
    return abort;
  }
  OdEntry& entry = entries_.at(Key(index, subindex));
  if (entry.access == OdEntry::Access::kReadOnly) return canopen::sdo_abort::kReadOnly;
  if (size != 0 && size != entry.size) return canopen::sdo_abort::kLengthMismatch;
  if (entry.size < 4) value &= (1u << (8 * entry.size)) - 1;
  if (const uint32_t abort = CheckValue(entry, value); abort != 0) return abort;
  entry.value = value;
  return 0;
}

uint32_t ObjectDictionary::Get(uint16_t index, uint8_t subindex) const {
  const OdEntry* entry = Find(index, subindex);
  if (!entry) throw std::logic_error("object dictionary: no entry " + std::to_string(index));
  return entry->value;
}

int32_t ObjectDictionary::GetSigned(uint16_t index, uint8_t subindex) const {
  const OdEntry* entry = Find(index, subindex);
  if (!entry) throw std::logic_error("object dictionary: no entry " + std::to_string(index));
  return canopen::SignExtend(entry->value, entry->size);
}

void ObjectDictionary::Set(uint16_t index, uint8_t subindex, uint32_t value) {
  const auto it = entries_.find(Key(index, subindex));
  if (it == entries_.end()) {
    throw std::logic_error("object dictionary: no entry " + std::to_string(index));
  }
  it->second.value = value;
}

void ObjectDictionary::ResetRange(uint16_t first_index, uint16_t last_index) {
  for (auto& [key, entry] : entries_) {
    const uint32_t index = key >> 8;
    if (index >= first_index && index <= last_index) entry.value = entry.default_value;
  }
}

}  // namespace shapesense
