#include "libs/actuation/can_bus.h"

#include <cstdio>

namespace shapesense {

std::string DescribeFrame(const CanFrame& frame) {
  char text[64];
  std::snprintf(text, sizeof(text), "0x%03X [%u]", frame.id, frame.size);
  std::string description = text;
  for (size_t i = 0; i < frame.size && i < frame.data.size(); ++i) {
    std::snprintf(text, sizeof(text), " %02X", frame.data[i]);
    description += text;
  }
  return description;
}

}  // namespace shapesense
