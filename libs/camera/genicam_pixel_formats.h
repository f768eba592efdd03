#pragma once

// GenICam PFNC pixel format codes, as Aravis's ARV_PIXEL_FORMAT_* (whose
// macros are C casts): shared by the capture service's Aravis backend, which
// decodes them, and the virtual rig's fake cameras, which encode them.
#include <cstdint>

namespace shapesense::genicam {

inline constexpr uint32_t kMono8 = 0x01080001u;
inline constexpr uint32_t kMono16 = 0x01100007u;
inline constexpr uint32_t kBayerGr8 = 0x01080008u;
inline constexpr uint32_t kBayerRg8 = 0x01080009u;
inline constexpr uint32_t kBayerGb8 = 0x0108000au;
inline constexpr uint32_t kBayerBg8 = 0x0108000bu;
inline constexpr uint32_t kRgb8 = 0x02180014u;
inline constexpr uint32_t kBgr8 = 0x02180015u;

}  // namespace shapesense::genicam
