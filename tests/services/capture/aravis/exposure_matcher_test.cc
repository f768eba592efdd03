// ExposureMatcher: random trigger streams of a camera whose timestamps are
// on the host's clock, with jitter in the trigger's round trip, missed
// triggers, lost frames and frames arriving up to two periods late. A
// camera within its latency gets every frame matched to the trigger that
// caused it; nothing is ever matched to another trigger; whatever cannot be
// proven is dropped with its reason.

#include "services/capture/exposure_matcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace shapesense {
namespace {

struct Scenario {
  int64_t period_us = 33'000;
  int64_t max_latency_us = 4'000;     // the matcher's bound
  int64_t latency_us = 3'000;         // the camera's actual longest latency
  int64_t round_trip_us = 800;        // longest send -> acknowledged
  int64_t arrival_delay_us = 66'000;  // longest exposure -> frame received
  double miss = 0.0;
  double lost = 0.0;
};

struct Frame {
  int64_t caused_by;  // trigger seq
  ExposureStamp stamp;
};

struct Stream {
  std::vector<SentTrigger> triggers;
  std::vector<Frame> frames;  // in arrival order
  int missing = 0;            // triggers that got no frame
};

Stream Simulate(const Scenario& s, int count, uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int64_t> round_trip(50, s.round_trip_us);
  std::uniform_int_distribution<int64_t> latency(0, s.latency_us);
  std::uniform_int_distribution<int64_t> delay(1'000, s.arrival_delay_us);
  std::bernoulli_distribution miss(s.miss), lost(s.lost);
  Stream stream;
  int64_t frame_id = 65'530;  // wraps 65535 -> 1 soon
  for (int k = 0; k < count; ++k) {
    const int64_t utime = 1'000'000'000 + k * s.period_us;
    const int64_t sent = utime + 200;
    const int64_t acked = sent + round_trip(rng);
    stream.triggers.push_back({k, utime, sent, acked});
    if (miss(rng)) {
      ++stream.missing;
      continue;
    }
    const int64_t received_by_camera = std::uniform_int_distribution<int64_t>(sent, acked)(rng);
    const int64_t exposure = received_by_camera + latency(rng);
    frame_id = frame_id % 65'535 + 1;
    if (lost(rng)) {
      ++stream.missing;
      continue;
    }
    stream.frames.push_back({k, {frame_id, exposure, exposure + delay(rng)}});
  }
  // A camera's frames leave in order; each arrives no earlier than the last.
  for (size_t i = 1; i < stream.frames.size(); ++i) {
    stream.frames[i].stamp.received_utime =
        std::max(stream.frames[i].stamp.received_utime, stream.frames[i - 1].stamp.received_utime);
  }
  return stream;
}

struct Outcome {
  int matched = 0;
  int wrong = 0;
  int rejected = 0;
};

// Replays the stream in time order: each trigger when it was acknowledged,
// each frame when it arrived.
Outcome Replay(const Scenario& s, const Stream& stream, ExposureMatcher* matcher) {
  Outcome outcome;
  size_t next_trigger = 0;
  for (const Frame& frame : stream.frames) {
    while (next_trigger < stream.triggers.size() &&
           stream.triggers[next_trigger].acked_utime <= frame.stamp.received_utime) {
      matcher->Sent(stream.triggers[next_trigger++]);
    }
    matcher->Expire(frame.stamp.received_utime);
    const MatchResult result = matcher->Match(frame.stamp);
    if (!result.trigger) {
      ++outcome.rejected;
    } else if (result.trigger->seq == frame.caused_by) {
      ++outcome.matched;
    } else {
      ++outcome.wrong;
    }
  }
  (void)s;
  return outcome;
}

ExposureMatcherOptions OptionsOf(const Scenario& s) {
  ExposureMatcherOptions options;
  options.max_latency_us = s.max_latency_us;
  return options;
}

TEST(ExposureMatcher, ACameraWithinItsLatencyHasEveryFrameMatchedToItsOwnTrigger) {
  for (uint32_t seed = 0; seed < 40; ++seed) {
    Scenario s;
    s.period_us = 3'500 + seed * 2'000;  // 286 Hz to 12 Hz
    s.max_latency_us = std::min<int64_t>(4'000, s.period_us - s.round_trip_us - 200);
    s.latency_us = s.max_latency_us;
    s.arrival_delay_us = 2 * s.period_us;
    s.miss = 0.1;
    s.lost = 0.05;
    const Stream stream = Simulate(s, 400, seed);
    ExposureMatcher matcher(OptionsOf(s));
    const Outcome outcome = Replay(s, stream, &matcher);
    EXPECT_EQ(outcome.wrong, 0) << "seed " << seed;
    EXPECT_EQ(outcome.rejected, 0) << "seed " << seed << ": " << matcher.DescribeRejections();
    EXPECT_EQ(outcome.matched, static_cast<int>(stream.frames.size()));
    for (const SentTrigger& trigger : stream.triggers) {
      if (trigger.acked_utime > stream.frames.back().stamp.received_utime) matcher.Sent(trigger);
    }
    matcher.Expire(stream.triggers.back().acked_utime + 10'000'000);
    EXPECT_EQ(matcher.unanswered(), stream.missing) << "seed " << seed;
  }
}

// Triggers closer than the window: frames inside two windows are dropped,
// never given to either trigger.
TEST(ExposureMatcher, FramesInOverlappingWindowsAreDroppedAsAmbiguous) {
  for (uint32_t seed = 0; seed < 20; ++seed) {
    Scenario s;
    s.period_us = 2'500;
    s.max_latency_us = 4'000;
    s.latency_us = 4'000;
    const Stream stream = Simulate(s, 300, seed);
    ExposureMatcher matcher(OptionsOf(s));
    const Outcome outcome = Replay(s, stream, &matcher);
    EXPECT_EQ(outcome.wrong, 0) << "seed " << seed;
    EXPECT_GT(matcher.count(MatchVerdict::kAmbiguous), 0);
    EXPECT_EQ(outcome.matched + outcome.rejected, static_cast<int>(stream.frames.size()));
  }
}

// A camera slower than its stated latency: its late frames fall outside
// every window, or inside the next trigger's (then that trigger's exposure
// time is what the image shows); each is dropped or matched to a trigger
// whose window holds its exposure, never beyond.
TEST(ExposureMatcher, AFrameIsOnlyEverMatchedToATriggerWhoseWindowHoldsItsExposure) {
  for (uint32_t seed = 0; seed < 20; ++seed) {
    Scenario s;
    s.latency_us = 40'000;  // ten times the bound
    const Stream stream = Simulate(s, 300, seed);
    ExposureMatcher matcher(OptionsOf(s));
    size_t next_trigger = 0;
    int outside = 0;
    for (const Frame& frame : stream.frames) {
      while (next_trigger < stream.triggers.size() &&
             stream.triggers[next_trigger].acked_utime <= frame.stamp.received_utime) {
        matcher.Sent(stream.triggers[next_trigger++]);
      }
      const MatchResult result = matcher.Match(frame.stamp);
      if (!result.trigger) continue;
      const SentTrigger& t = *result.trigger;
      if (frame.stamp.exposure_utime < t.sent_utime ||
          frame.stamp.exposure_utime > t.acked_utime + s.max_latency_us) {
        ++outside;
      }
    }
    EXPECT_EQ(outside, 0);
    EXPECT_GT(matcher.count(MatchVerdict::kOutsideWindows), 0);
  }
}

class ExposureMatcherCase : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int64_t k = 0; k < 3; ++k) {
      matcher_.Sent({k, 1'000'000 + k * 10'000, 1'000'100 + k * 10'000, 1'000'500 + k * 10'000});
    }
  }
  // A frame exposed `after_us` after trigger k was sent, received 5 ms later.
  static ExposureStamp FrameOf(int64_t k, int64_t frame_id, int64_t after_us = 300) {
    const int64_t exposure = 1'000'100 + k * 10'000 + after_us;
    return {frame_id, exposure, exposure + 5'000};
  }
  ExposureMatcher matcher_;
};

TEST_F(ExposureMatcherCase, MatchesFramesArrivingInAnyOrderOfTriggers) {
  EXPECT_EQ(matcher_.Match(FrameOf(0, 10)).trigger->seq, 0);
  EXPECT_EQ(matcher_.Match(FrameOf(2, 12)).trigger->seq, 2) << "trigger 1 missed";
  EXPECT_EQ(matcher_.rejected(), 0);
}

TEST_F(ExposureMatcherCase, DropsADuplicateFrame) {
  ASSERT_TRUE(matcher_.Match(FrameOf(0, 10)).trigger);
  EXPECT_EQ(matcher_.Match(FrameOf(0, 10)).verdict, MatchVerdict::kRepeatedFrameId);
}

TEST_F(ExposureMatcherCase, DropsASecondFrameForOneTrigger) {
  ASSERT_TRUE(matcher_.Match(FrameOf(1, 10)).trigger);
  EXPECT_EQ(matcher_.Match(FrameOf(1, 11, 900)).verdict, MatchVerdict::kAnsweredAlready);
}

TEST_F(ExposureMatcherCase, DropsAFrameIdGoingBackwards) {
  ASSERT_TRUE(matcher_.Match(FrameOf(1, 10)).trigger);
  EXPECT_EQ(matcher_.Match(FrameOf(2, 9)).verdict, MatchVerdict::kFrameIdBackwards);
  EXPECT_EQ(matcher_.Match(FrameOf(2, 11)).trigger->seq, 2) << "the next good one is taken";
}

TEST_F(ExposureMatcherCase, AcceptsTheGigEVisionBlockIdWrap) {
  ASSERT_TRUE(matcher_.Match(FrameOf(0, 65'535)).trigger);
  EXPECT_EQ(matcher_.Match(FrameOf(1, 1)).trigger->seq, 1);
}

TEST_F(ExposureMatcherCase, DropsATimestampInTheFutureOrMissing) {
  ExposureStamp future = FrameOf(1, 10);
  future.received_utime = future.exposure_utime - 10'000;
  EXPECT_EQ(matcher_.Match(future).verdict, MatchVerdict::kFutureTimestamp);
  ExposureStamp none = FrameOf(1, 11);
  none.exposure_utime = 0;
  EXPECT_EQ(matcher_.Match(none).verdict, MatchVerdict::kNoTimestamp);
  EXPECT_EQ(matcher_.rejected(), 2);
  EXPECT_NE(matcher_.DescribeRejections().find("1 frames stamped after they arrived"),
            std::string::npos)
      << matcher_.DescribeRejections();
}

TEST_F(ExposureMatcherCase, DropsAnExposureBeforeItsTriggerLeftOrPastItsLatency) {
  EXPECT_EQ(matcher_.Match(FrameOf(0, 10, -50)).verdict, MatchVerdict::kOutsideWindows);
  EXPECT_EQ(matcher_.Match(FrameOf(0, 11, 400 + 4'001)).verdict, MatchVerdict::kOutsideWindows);
  EXPECT_EQ(matcher_.Match(FrameOf(0, 12, 400 + 4'000)).trigger->seq, 0);
}

// A trigger that reached a busy camera long after its frame-set's time:
// its frame shows a later moment than the set's time says.
TEST_F(ExposureMatcherCase, DropsAFrameExposedTooLongAfterItsFrameSetsTime) {
  matcher_.Sent({3, 1'040'000, 1'040'100, 1'040'100 + 12'000});
  EXPECT_EQ(matcher_.Match({20, 1'040'000 + 10'001, 1'060'000}).verdict,
            MatchVerdict::kLateExposure);
  matcher_.Sent({4, 1'050'000, 1'060'000, 1'060'200});
  EXPECT_EQ(matcher_.Match({21, 1'060'000, 1'070'000}).trigger->seq, 4) << "10 ms after: kept";
  EXPECT_EQ(matcher_.count(MatchVerdict::kLateExposure), 1);
  EXPECT_EQ(matcher_.unanswered(), 1) << "its trigger got no usable frame";
}

// The sender may be held up between the camera's acknowledgement and its
// note of it: a frame arriving meanwhile still finds its trigger's window,
// which is open from the moment the trigger left.
TEST_F(ExposureMatcherCase, AFrameBeforeTheAcknowledgementIsNotedFindsItsOpenWindow) {
  matcher_.Sending(3, 1'040'000, 1'040'100);
  EXPECT_EQ(matcher_.Match({20, 1'040'400, 1'045'000}).trigger->seq, 3);
  matcher_.Acknowledged(3, 1'040'300);
  matcher_.Sending(4, 1'050'000, 1'050'100);
  EXPECT_EQ(matcher_.Match({21, 1'050'000, 1'055'000}).verdict, MatchVerdict::kOutsideWindows)
      << "exposed before its trigger left";
  matcher_.Acknowledged(4, 1'050'300);
  EXPECT_EQ(matcher_.Match({22, 1'050'300 + 4'001, 1'060'000}).verdict,
            MatchVerdict::kOutsideWindows)
      << "once acknowledged, the window closes the latency later";
}

TEST_F(ExposureMatcherCase, CountsUnansweredTriggersOnceTheirWindowsPassed) {
  ASSERT_TRUE(matcher_.Match(FrameOf(1, 10)).trigger);
  matcher_.Expire(1'000'000 + 20'000);
  EXPECT_EQ(matcher_.unanswered(), 0) << "still kept for late frames";
  matcher_.Expire(1'000'000 + 2'000'000);
  EXPECT_EQ(matcher_.unanswered(), 2);
}

TEST_F(ExposureMatcherCase, ResetForgetsTriggersAndFrameIds) {
  ASSERT_TRUE(matcher_.Match(FrameOf(0, 500)).trigger);
  matcher_.Reset();
  EXPECT_EQ(matcher_.unanswered(), 2);
  matcher_.Sent({7, 2'000'000, 2'000'100, 2'000'500});
  EXPECT_EQ(matcher_.Match({1, 2'000'400, 2'005'000}).trigger->seq, 7)
      << "a reopened camera counts from 1 again";
}

}  // namespace
}  // namespace shapesense
