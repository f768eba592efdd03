#include "runtime/lcm/stage_times.h"

#include <algorithm>

#include "libs/core/error.h"

namespace shapesense {

std::string ValidateStageTimes(int32_t count, const std::vector<stage_time_t>& stages) {
  if (count < 0 || static_cast<size_t>(count) != stages.size()) {
    return Expected("num_stage_times", std::to_string(stages.size()) + " (the stages sent)",
                    std::to_string(count));
  }
  for (const stage_time_t& stage : stages) {
    if (stage.stage.empty()) return Expected("stage_times.stage", "a name", "an empty one");
    if (stage.duration_us < 0) {
      return Expected("stage_times[" + stage.stage + "].duration_us", ">= 0",
                      std::to_string(stage.duration_us));
    }
  }
  return {};
}

stage_time_t MakeStageTime(const std::string& stage, int64_t duration_us, int64_t end_utime) {
  stage_time_t time{};
  time.stage = stage;
  time.duration_us = duration_us;
  time.end_utime = end_utime;
  return time;
}

const stage_time_t* FindStageTime(const std::vector<stage_time_t>& stages,
                                  const std::string& stage) {
  for (const stage_time_t& time : stages) {
    if (time.stage == stage) return &time;
  }
  return nullptr;
}

void MergeStageTime(const stage_time_t& stage, std::vector<stage_time_t>* stages) {
  for (stage_time_t& time : *stages) {
    if (time.stage != stage.stage) continue;
    time.duration_us = std::max(time.duration_us, stage.duration_us);
    time.end_utime = std::max(time.end_utime, stage.end_utime);
    return;
  }
  stages->push_back(stage);
}

}  // namespace shapesense
