#include "runtime/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace shapesense {

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled && isatty(STDERR_FILENO) == 1) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Update(double fraction, const std::string& detail) {
  if (!enabled_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (fraction < 1.0 && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  Draw(fraction, detail);
}

void ProgressBar::Finish() {
  if (!enabled_ || finished_) return;
  Draw(1.0, "done");
  std::fputc('\n', stderr);
  finished_ = true;
}

void ProgressBar::Draw(double fraction, const std::string& detail) {
  constexpr int kWidth = 30;
  const double clamped = std::clamp(fraction, 0.0, 1.0);
  const int filled = static_cast<int>(std::lround(clamped * kWidth));
  std::string bar(static_cast<size_t>(filled), '#');
  bar.append(static_cast<size_t>(kWidth - filled), '.');
  std::fprintf(stderr, "\r%s [%s] %3d%% %s\033[K", label_.c_str(), bar.c_str(),
               static_cast<int>(clamped * 100.0), detail.c_str());
  std::fflush(stderr);
}

}  // namespace shapesense
