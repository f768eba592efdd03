#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace shapesense {

// A progress bar on stderr when it is a terminal; silent otherwise (logs and
// CI stay clean). Updates at most 10 times a second.
class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled = true);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // fraction in [0, 1]; `detail` is shown after the bar (e.g. "frame 12/40").
  void Update(double fraction, const std::string& detail = {});
  void Finish();

 private:
  void Draw(double fraction, const std::string& detail);

  std::string label_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point last_draw_{};
};

}  // namespace shapesense
