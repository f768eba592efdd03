#pragma once

// A CPU hog for the timing-robustness tests: one thread that keeps a core
// busy until it is destroyed or its deadline passes, whichever is first, so
// a failing test never leaves it running.

#include <atomic>
#include <chrono>
#include <thread>

namespace shapesense::testing_support {

class CpuHog {
 public:
  explicit CpuHog(std::chrono::seconds limit) {
    thread_ = std::thread([this, end = std::chrono::steady_clock::now() + limit] {
      uint64_t x = 1;
      while (!stop_ && std::chrono::steady_clock::now() < end) {
        for (int i = 0; i < 100'000; ++i) x = x * 6364136223846793005ULL + 1442695040888963407ULL;
        sink_ = x;
      }
    });
  }
  ~CpuHog() {
    stop_ = true;
    thread_.join();
  }
  CpuHog(const CpuHog&) = delete;
  CpuHog& operator=(const CpuHog&) = delete;

 private:
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> sink_{0};
  std::thread thread_;
};

}  // namespace shapesense::testing_support
