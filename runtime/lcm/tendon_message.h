#pragma once

// What a tendon command's fields mean, in words, for logs and views.
#include <cstdint>

namespace shapesense {

// "hold", "open_loop", "closed_loop", "model_less", "stop"
// (tendon_command_t::MODE_*); "unknown" for any other value.
const char* CommandModeName(int8_t mode);

}  // namespace shapesense
