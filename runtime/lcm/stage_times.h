#pragma once

// The stage times every pipeline message carries (stage_time_t): how long
// each stage took on a frame-set, and when it ended.
#include <cstdint>
#include <string>
#include <vector>

#include "shapesense/stage_time_t.hpp"

namespace shapesense {

stage_time_t MakeStageTime(const std::string& stage, int64_t duration_us, int64_t end_utime);
// The stage of that name, or nullptr.
const stage_time_t* FindStageTime(const std::vector<stage_time_t>& stages,
                                  const std::string& stage);
// Adds a stage; when one of that name is there already (the images of a
// frame-set each carry their own "capture"), keeps the later end and the
// longer duration: the frame-set waited for its slowest image.
void MergeStageTime(const stage_time_t& stage, std::vector<stage_time_t>* stages);

// "" when `count` matches the stages sent and each has a name and a
// non-negative duration; else the reason (a field of a message off the network).
std::string ValidateStageTimes(int32_t count, const std::vector<stage_time_t>& stages);

}  // namespace shapesense
