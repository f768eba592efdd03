// TriggerMatcher: random trigger streams with lost frames, missed triggers,
// jitter, pipelining (frames arriving after the next trigger) and arbitrary
// device clocks; every delivered frame must get the trigger that made it.

#include "services/capture/aravis_trigger_matcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace shapesense {
namespace {

struct Scenario {
  int64_t period_us;   // between triggers
  int64_t latency_us;  // exposure start to frame received (may exceed the period)
  double miss = 0.0;   // the camera ignores a trigger
  double lost = 0.0;   // the frame never arrives
  double incomplete = 0.0;
  bool device_clock = true;
};

struct Event {
  int64_t time_us;
  bool is_trigger;
  int64_t seq;  // trigger seq; for a frame, the trigger that made it
  FrameTiming frame;
};

// Triggers and frame arrivals of one run, in time order. The first three
// triggers always make frames (the matcher anchors on the first frame).
std::vector<Event> Simulate(const Scenario& s, int triggers, uint32_t seed, int* expected_stale) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int64_t clock_offset_us = static_cast<int64_t>(unit(rng) * 1e12) + 1'000'000;
  std::vector<Event> events;
  int64_t frame_id = 65530;  // wraps 65535 -> 1 soon
  *expected_stale = 0;
  for (int k = 0; k < triggers; ++k) {
    const int64_t sent = 1'000'000 + k * s.period_us + static_cast<int64_t>(unit(rng) * 500);
    events.push_back({sent, true, k, {}});
    if (k >= 3 && unit(rng) < s.miss) {
      ++*expected_stale;
      continue;
    }
    const int64_t exposure = sent + 100 + static_cast<int64_t>(unit(rng) * 900);
    frame_id = frame_id % 65535 + 1;
    if (k >= 3 && unit(rng) < s.lost) {
      ++*expected_stale;
      continue;
    }
    const int64_t received = exposure + s.latency_us + static_cast<int64_t>(unit(rng) * 1500);
    const int64_t device_ns = s.device_clock ? (exposure + clock_offset_us) * 1000 : 0;
    // Grab() takes it a little after it arrived.
    events.push_back({received + static_cast<int64_t>(unit(rng) * 2000), false, k,
                      FrameTiming{frame_id, device_ns, received}});
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& a, const Event& b) { return a.time_us < b.time_us; });
  return events;
}

void ExpectEveryFrameMatched(const Scenario& s, uint32_t seed) {
  int expected_stale = 0;
  const std::vector<Event> events = Simulate(s, 300, seed, &expected_stale);
  TriggerMatcher matcher;
  int frames = 0;
  for (const Event& event : events) {
    if (event.is_trigger) {
      matcher.Sent({event.seq, event.seq * 10, event.time_us});
      continue;
    }
    const std::optional<PendingTrigger> match = matcher.Match(event.frame);
    ASSERT_TRUE(match.has_value()) << "seed " << seed << ": frame of trigger " << event.seq;
    ASSERT_EQ(match->seq, event.seq) << "seed " << seed << ", period " << s.period_us
                                     << " us, latency " << s.latency_us << " us";
    EXPECT_EQ(match->utime, event.seq * 10);
    ++frames;
  }
  EXPECT_GT(frames, 100);
  EXPECT_LE(matcher.stale(), expected_stale) << "stale triggers are dropped, never frames";
}

TEST(TriggerMatcher, MatchesInOrderWhenNothingGoesWrong) {
  for (uint32_t seed = 0; seed < 10; ++seed) {
    ExpectEveryFrameMatched({20'000, 8'000}, seed);
  }
}

TEST(TriggerMatcher, LostFramesAndMissedTriggersNeverShiftLaterFrames) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int64_t> period(8'000, 40'000);
  for (uint32_t seed = 0; seed < 40; ++seed) {
    const int64_t p = period(rng);
    // Frames arrive before, or up to 1.8 periods after, the next trigger.
    const int64_t latency = 1'000 + static_cast<int64_t>((seed % 10) * 0.2 * p);
    ExpectEveryFrameMatched({p, latency, 0.05, 0.05, 0.0}, seed);
  }
}

TEST(TriggerMatcher, CountsFrameIdsWithoutDeviceTimestamps) {
  for (uint32_t seed = 0; seed < 20; ++seed) {
    Scenario s{15'000, 5'000 + seed * 1'000, 0.0, 0.08, 0.0, /*device_clock=*/false};
    ExpectEveryFrameMatched(s, seed);
  }
}

TEST(TriggerMatcher, AFrameNoTriggerWasSentForIsNotMatched) {
  TriggerMatcher matcher;
  matcher.Sent({0, 0, 2'000});
  EXPECT_FALSE(matcher.Match({1, 5'000'000, 1'000}).has_value()) << "arrived before the trigger";
  EXPECT_EQ(matcher.pending(), 1u);
  EXPECT_EQ(matcher.Match({2, 5'000'000, 3'000})->seq, 0);
  EXPECT_FALSE(matcher.Match({3, 6'000'000, 9'000}).has_value()) << "nothing pending";
}

TEST(TriggerMatcher, KeepsABoundedQueueAndForgetsOnReset) {
  TriggerMatcher matcher(4);
  for (int k = 0; k < 10; ++k) matcher.Sent({k, 0, k * 1'000});
  EXPECT_EQ(matcher.pending(), 4u);
  EXPECT_EQ(matcher.stale(), 6);
  EXPECT_EQ(matcher.Match({0, 0, 100'000})->seq, 6);
  matcher.Reset();
  EXPECT_EQ(matcher.pending(), 0u);
}

}  // namespace
}  // namespace shapesense
