// `shapesense rig status`: every expected program of the rig file is up,
// stale or missing by its status; programs heard but not expected are
// shown as such; the table and JSON carry the process, the health and the
// clock offsets; the command exits non-zero while a program is missing.
#include "runtime/rig/rig_status.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "runtime/file_io.h"

namespace shapesense {
namespace {

const std::filesystem::path kExample =
    std::filesystem::path(SHAPESENSE_SOURCE_DIR) / "config" / "rig.yaml";

service_status_t Status(const std::string& host, const std::string& service) {
  service_status_t status{};
  status.host = host;
  status.service = service;
  status.pid = 4242;
  status.uptime_s = 12;
  status.cpu_percent = 37.5F;
  status.rss_bytes = 50'000'000;
  status.num_clock_offsets = 1;
  status.clock_offset_hosts = {"control"};
  status.clock_offsets_us = {-2'500};
  status.clock_warning = "control's clock is -2.500 ms off this host's (> 1 ms)";
  return status;
}

TEST(RigStatusTest, ExpectedProgramsAreUpStaleOrMissingAndStrangersAreShown) {
  RigStatusBoard board(ParseRigFile(ReadTextFile(kExample), kExample));
  const int64_t t0 = 1'000'000'000'000;
  for (const char* service : {"capture", "carving", "shape"}) {
    board.Observe(Status("camera", service), t0);
  }
  board.Observe(Status("laptop", "shape"), t0);
  std::vector<RigStatusRow> rows = board.Rows(t0 + 500'000);
  ASSERT_EQ(rows.size(), 6u);  // capture, carving, shape, controller, monitor; the stranger
  std::map<std::string, ProgramState> state;
  for (const RigStatusRow& row : rows) state[row.host + "/" + row.service] = row.state;
  EXPECT_EQ(state["camera/carving"], ProgramState::kUp);
  EXPECT_EQ(state["control/controller"], ProgramState::kMissing);
  EXPECT_EQ(state["operator/monitor"], ProgramState::kMissing);
  EXPECT_EQ(state["laptop/shape"], ProgramState::kUnexpected);
  EXPECT_FALSE(board.Complete(t0 + 500'000));
  board.Observe(Status("control", "controller"), t0 + 600'000);
  board.Observe(Status("operator", "monitor"), t0 + 600'000);
  EXPECT_TRUE(board.Complete(t0 + 700'000));
  // Four seconds without a word from the camera host: stale.
  EXPECT_FALSE(board.Complete(t0 + 4'000'000));
  rows = board.Rows(t0 + 4'000'000);
  EXPECT_EQ(rows.front().state, ProgramState::kStale);
  EXPECT_NEAR(rows.front().status_age_s, 4.0, 1e-9);
}

// Without a rig file (the web monitor's view): what is heard is expected,
// stale after one missed status, missing after two and a half.
TEST(RigStatusTest, WithoutARigFileAProgramHeardAndFallenSilentIsMissing) {
  RigStatusBoard board(std::nullopt, 1.6, 2.5, /*expect_heard=*/true);
  const int64_t t0 = 1'000'000'000'000;
  board.Observe(Status("camera", "shape"), t0);
  const auto state = [&](int64_t age_us) { return board.Rows(t0 + age_us).at(0).state; };
  EXPECT_EQ(state(1'000'000), ProgramState::kUp);
  EXPECT_EQ(state(2'000'000), ProgramState::kStale);
  EXPECT_EQ(state(2'600'000), ProgramState::kMissing);
  RigStatusBoard plain(std::nullopt);  // `rig status` without a file: strangers, never missing
  plain.Observe(Status("camera", "shape"), t0);
  EXPECT_EQ(plain.Rows(t0 + 60'000'000).at(0).state, ProgramState::kUnexpected);
}

TEST(RigStatusTest, TableAndJsonCarryTheHealthOffsetsAndStages) {
  RigStatusBoard board(ParseRigFile(ReadTextFile(kExample), kExample));
  const int64_t t0 = 1'000'000'000'000;
  board.Observe(Status("camera", "carving"), t0);
  shape_t shape{};
  shape.stage_times = {{"capture", 900, 0}, {"carving", 1'600, 0}};
  shape.num_stage_times = 2;
  board.Observe(shape);
  const std::string table = board.Table(t0);
  EXPECT_NE(table.find("camera     carving     up"), std::string::npos) << table;
  EXPECT_NE(table.find("control    controller  missing"), std::string::npos) << table;
  EXPECT_NE(table.find("-2.500"), std::string::npos) << table;
  EXPECT_NE(table.find("carving 1.60"), std::string::npos) << table;
  const nlohmann::json json = nlohmann::json::parse(board.Json(t0));
  EXPECT_FALSE(json.at("complete").get<bool>());
  EXPECT_DOUBLE_EQ(json.at("stage_latency_ms").at("capture").get<double>(), 0.9);
  bool seen = false;
  for (const nlohmann::json& row : json.at("programs")) {
    if (row.at("program") != "carving") continue;
    seen = true;
    EXPECT_EQ(row.at("pid").get<int>(), 4242);
    EXPECT_EQ(row.at("rss_bytes").get<int64_t>(), 50'000'000);
    EXPECT_DOUBLE_EQ(row.at("clock_offsets_ms").at("control").get<double>(), -2.5);
  }
  EXPECT_TRUE(seen);
}

TEST(RigStatusTest, TheCommandExitsNonZeroWhileAProgramIsMissing) {
  const std::string command = std::string(SHAPESENSE_BIN_DIR) +
                              "/shapesense rig status --once --rig " + kExample.string() +
                              " --lcm-url memq:// 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  std::array<char, 512> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe) != nullptr) output += buffer.data();
  const int status = pclose(pipe);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << status << "\n" << output;
  EXPECT_NE(output.find("camera     capture     missing"), std::string::npos) << output;
  EXPECT_NE(output.find("missing or stale"), std::string::npos) << output;
}

}  // namespace
}  // namespace shapesense
