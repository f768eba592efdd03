// A real service program under a supervisor as systemd runs it: the
// shapesense-shape binary with NOTIFY_SOCKET and WATCHDOG_USEC says READY=1,
// pings the watchdog from its loop, and says STOPPING=1 after SIGTERM, then
// exits 0. Every wait is bounded and generous (the sanitizer builds are slow).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <filesystem>

#include "runtime/process/child_process.h"
#include "tests/runtime/process/notify_socket.h"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;

TEST(SupervisedProgram, ShapeServiceSaysReadyPingsAndSaysStoppingOnSigterm) {
  const fs::path folder = fs::temp_directory_path() / ("supervised_" + std::to_string(getpid()));
  fs::create_directories(folder);
  testing::TestRig().WriteFiles(folder);
  testing::NotifySocket socket(/*watchdog_usec=*/500'000);
  ChildOptions options;
  options.capture_stderr = true;
  ChildProcess shape({std::string(PROGRAM_DIR) + "/shapesense-shape", "--rig",
                      (folder / "rig.yaml").string(), "--lcm-url", "memq://"},
                     options);

  ASSERT_TRUE(socket.WaitFor("READY=1", milliseconds(seconds(60))))
      << socket.Transcript() << (shape.ReadAvailable(), shape.output());
  EXPECT_TRUE(socket.WaitFor("WATCHDOG=1", milliseconds(seconds(10)))) << socket.Transcript();
  shape.Signal(SIGTERM);
  EXPECT_TRUE(socket.WaitFor("STOPPING=1", milliseconds(seconds(10)))) << socket.Transcript();
  const int status = shape.Stop();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << DescribeExitStatus(status) << "\n"
                                                             << shape.output();
  fs::remove_all(folder);
}

}  // namespace
}  // namespace shapesense
