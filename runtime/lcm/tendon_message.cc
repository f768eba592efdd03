#include "runtime/lcm/tendon_message.h"

#include "shapesense/tendon_command_t.hpp"

namespace shapesense {

const char* CommandModeName(int8_t mode) {
  switch (mode) {
    case tendon_command_t::MODE_HOLD:
      return "hold";
    case tendon_command_t::MODE_OPEN_LOOP:
      return "open_loop";
    case tendon_command_t::MODE_CLOSED_LOOP:
      return "closed_loop";
    case tendon_command_t::MODE_MODEL_LESS:
      return "model_less";
    case tendon_command_t::MODE_STOP:
      return "stop";
    default:
      return "unknown";
  }
}

}  // namespace shapesense
