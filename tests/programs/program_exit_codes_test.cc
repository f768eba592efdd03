// Every shapesense program, run as a user runs it, gives one meaning to its
// exit code: 2 for bad input (an unknown option, a broken config file), with
// a message naming what is wrong, and 0 after --help.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/process/child_process.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

struct ProgramRun {
  int exit_code = -1;
  std::string output;
};

// Runs the program to its end (bounded: killed after 60 s).
ProgramRun RunProgram(const std::vector<std::string>& argv) {
  ChildOptions options;
  options.capture_stderr = true;
  ChildProcess child(argv, options);
  child.WaitForLine("\x01 never printed", std::chrono::seconds(60));
  const int status = child.Stop(std::chrono::milliseconds(100));
  return {status >= 0 && WIFEXITED(status) ? WEXITSTATUS(status) : -1, child.output()};
}

std::string Program(const std::string& name) { return std::string(PROGRAM_DIR) + "/" + name; }

class ProgramExitCodesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() / ("exit_codes_" + std::to_string(getpid()));
    fs::create_directories(folder_);
    std::ofstream(broken_config()) << "options: [\n";
  }
  void TearDown() override { fs::remove_all(folder_); }
  std::string broken_config() const { return (folder_ / "broken.yaml").string(); }

  fs::path folder_;
};

TEST_F(ProgramExitCodesTest, ABrokenConfigFileIsBadInputNamedInEveryProgram) {
  const std::vector<std::vector<std::string>> runs = {
      {Program("shapesense-capture"), "--config", broken_config()},
      {Program("shapesense-carving"), "--config", broken_config()},
      {Program("shapesense-shape"), "--config", broken_config()},
      {Program("shapesense-controller"), "--config", broken_config()},
      {Program("shapesense-rig-sim"), "--trajectory", broken_config()},
  };
  for (const std::vector<std::string>& argv : runs) {
    const ProgramRun run = RunProgram(argv);
    EXPECT_EQ(run.exit_code, 2) << argv[0] << ":\n" << run.output;
    EXPECT_NE(run.output.find("broken.yaml"), std::string::npos) << argv[0] << ":\n" << run.output;
  }
}

TEST_F(ProgramExitCodesTest, AnUnknownOptionIsBadInputAndHelpIsNot) {
  for (const char* name :
       {"shapesense", "shapesense-capture", "shapesense-carving", "shapesense-shape",
        "shapesense-controller", "shapesense-rig-sim", "shapesense-actuator-sim"}) {
    const ProgramRun unknown = RunProgram({Program(name), "--no-such-option"});
    EXPECT_EQ(unknown.exit_code, 2) << name << ":\n" << unknown.output;
    // What is wrong is named (the option, or a required one missing first).
    EXPECT_NE(unknown.output.find("Run with --help"), std::string::npos) << name;
    const ProgramRun help = RunProgram({Program(name), "--help"});
    EXPECT_EQ(help.exit_code, 0) << name << ":\n" << help.output;
    EXPECT_NE(help.output.find("--help"), std::string::npos) << name;
  }
}

}  // namespace
}  // namespace shapesense
