// The live pipeline over two hosts (network namespaces on a bridge,
// runtime/process/virtual_hosts.h): the rig-sim, capture and carving on the
// camera host, the shape service on another host whose clock is half a
// second ahead. The compact messages cross the rig network (ttl=1), the
// images stay on the camera host, and the shapes are as exact as on one
// host: every shape of its own trigger within 0.5 mm, its age dated on
// local clocks whatever the offset, and each host's offset measured.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "tests/e2e/live_pipeline.h"
#include "tests/support/network_test.h"

namespace shapesense::e2e {
namespace {

constexpr double kRunSeconds = 6.0;
constexpr double kShapeHostAheadMs = 500.0;

double OffsetOf(const service_status_t& status, const std::string& host) {
  for (size_t i = 0; i < status.clock_offset_hosts.size(); ++i) {
    if (status.clock_offset_hosts[i] == host) {
      return static_cast<double>(status.clock_offsets_us[i]) * 1e-3;
    }
  }
  return std::nan("");
}

TEST(TwoHostPipelineTest, AShapeServiceOnAnotherHostHalfASecondAheadMeasuresAsOnOneHost) {
  ASSERT_EQ(nettest::PrivateNetworkError(), "");
  const VirtualHosts hosts({{kCameraHost, 0.0, 3}, {kShapeHost, kShapeHostAheadMs, 0}});
  PipelineOptions options;
  options.rate_hz = LiveRate();
  options.hosts = &hosts;
  LivePipeline pipeline("two_hosts", options);
  ASSERT_EQ(pipeline.StartServices(), "");
  const VirtualHosts::LinkBytes before = hosts.Bytes(kShapeHost);
  ASSERT_EQ(pipeline.RunCapture(kRunSeconds), "");
  const VirtualHosts::LinkBytes after = hosts.Bytes(kShapeHost);
  pipeline.Drain();
  const Recorder& recorder = pipeline.recorder();
  const int64_t end = pipeline.capture_end_utime() - 500'000;
  const Score score =
      ScoreShapes(recorder.Truths(), recorder.Shapes(), end, PairingToleranceUs(options.rate_hz));
  std::cout << Report(score, recorder);

  // As exact as on one host.
  EXPECT_GE(score.truths, 0.8 * options.rate_hz * (kRunSeconds - 1.0));
  EXPECT_EQ(score.matched, score.valid) << BadShapes(score, 0.5);
  EXPECT_LT(score.rms_max, 0.5) << BadShapes(score, 0.5);
  EXPECT_LE(score.unmeasured, 0.02 * score.truths + 1);

  // Each shape's age was summed on local clocks: dated on the recorder's
  // (the camera host's) clock it falls on its own trigger time, within the
  // hops' transit, not half a second off.
  int dated = 0;
  for (const Received<shape_t>& shape : recorder.Shapes()) {
    const int64_t measured = shape.receive_utime - shape.message.header.data_age_us;
    EXPECT_NEAR(static_cast<double>(measured - shape.message.trigger_utime) * 1e-3, 0.0, 50.0)
        << "shape of trigger " << shape.message.trigger_seq << ", age "
        << shape.message.header.data_age_us << " µs";
    EXPECT_EQ(shape.message.header.host, kShapeHost);
    ++dated;
  }
  EXPECT_GT(dated, 0);

  // Each side measured the other's clock from the traffic it receives.
  const auto shape_status = recorder.LastStatus("shape");
  const auto carving_status = recorder.LastStatus("carving");
  ASSERT_TRUE(shape_status && carving_status);
  EXPECT_EQ(shape_status->host, kShapeHost);
  EXPECT_NEAR(OffsetOf(*shape_status, kCameraHost), -kShapeHostAheadMs, 20.0);
  EXPECT_NEAR(OffsetOf(*carving_status, kShapeHost), kShapeHostAheadMs, 20.0);
  EXPECT_NE(shape_status->clock_warning.find(kCameraHost), std::string::npos);

  // The images (3 VGA views at the trigger rate, ~0.9 MB each) never
  // crossed: the shape host received compact messages only.
  const double seconds = kRunSeconds;
  const double received_per_s = static_cast<double>(after.received - before.received) / seconds;
  const double images_per_s = 3 * 640 * 480 * 3 * options.rate_hz;
  std::cout << "shape host received " << received_per_s / 1e3
            << " kB/s (the images: " << images_per_s / 1e3 << " kB/s)\n";
  EXPECT_LT(received_per_s, 0.05 * images_per_s);
  EXPECT_EQ(shape_status->dropped + shape_status->rejected + shape_status->errors, 0)
      << Describe(*shape_status);
  EXPECT_EQ(pipeline.StopAll(), "");
}

}  // namespace
}  // namespace shapesense::e2e
