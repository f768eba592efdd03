// ChildProcess (runtime/process), as the demo uses it: output with or
// without stderr, into a log file too; a program that cannot start named in
// the error; exit status without waiting; a stop that reads the last words
// and kills what does not stop; a nice value; a process group of its own;
// and a child that ends with the thread that started it.
#include "runtime/process/child_process.h"
#include "runtime/process/listening_socket.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <thread>

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;

std::vector<std::string> Shell(const std::string& script) { return {"/bin/sh", "-c", script}; }

// Reads until the child has ended (bounded); its status.
int WaitForEnd(ChildProcess& child) {
  for (int i = 0; i < 1000; ++i) {
    child.ReadAvailable();
    if (const std::optional<int> status = child.ExitStatus()) {
      child.ReadAvailable();
      return *status;
    }
    std::this_thread::sleep_for(milliseconds(10));
  }
  return -2;
}

TEST(ChildProcessTest, KeepsStdoutAndOnRequestStderr) {
  ChildProcess plain(Shell("echo out; echo err >&2"));
  ASSERT_TRUE(plain.WaitForLine("out", milliseconds(5000)));
  WaitForEnd(plain);
  EXPECT_EQ(plain.output().find("err"), std::string::npos);

  ChildOptions options;
  options.capture_stderr = true;
  options.log_file = fs::path(::testing::TempDir()) / "child_process_test.log";
  fs::remove(options.log_file);
  ChildProcess both(Shell("echo out; echo err >&2; exit 3"), options);
  EXPECT_EQ(WaitForEnd(both), 3 << 8);
  EXPECT_NE(both.output().find("out"), std::string::npos);
  EXPECT_NE(both.output().find("err"), std::string::npos);
  std::stringstream logged;
  logged << std::ifstream(options.log_file).rdbuf();
  EXPECT_EQ(logged.str(), both.output());
  fs::remove(options.log_file);
}

// Lowering the priority needs no privilege, so this holds for any user;
// `nice` without arguments prints the niceness it runs at.
TEST(ChildProcessTest, RunsAtTheNiceValueAsked) {
  ChildOptions options;
  options.capture_stderr = true;
  options.nice = 7;
  ChildProcess child({"/usr/bin/nice"}, options);
  EXPECT_EQ(WaitForEnd(child), 0);
  EXPECT_EQ(child.output(), "7\n");

  ChildProcess unchanged({"/usr/bin/nice"});
  EXPECT_EQ(WaitForEnd(unchanged), 0);
  EXPECT_EQ(unchanged.output(), std::to_string(getpriority(PRIO_PROCESS, 0)) + "\n");
}

TEST(ChildProcessTest, AProgramThatCannotStartIsNamed) {
  const std::string missing = "/nonexistent/shapesense-nothing";
  try {
    ChildProcess child({missing});
    FAIL() << "started a missing program";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
}

// A namespace fd that is none (here /dev/null) is refused by setns in the
// child: the parent hears which step failed, not a bare exit status.
TEST(ChildProcessTest, ANetworkNamespaceRefusedIsNamed) {
  const int not_a_namespace = open("/dev/null", O_RDONLY | O_CLOEXEC);
  ASSERT_GE(not_a_namespace, 0);
  ChildOptions options;
  options.network_namespace = not_a_namespace;
  try {
    ChildProcess child({"/bin/true"}, options);
    FAIL() << "started in a network namespace that is none";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/bin/true"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("setns"), std::string::npos) << e.what();
  }
  close(not_a_namespace);
}

TEST(ChildProcessTest, SetsTheEnvironmentAsked) {
  setenv("SHAPESENSE_CHILD_TEST_KEPT", "parent", 1);
  setenv("SHAPESENSE_CHILD_TEST_REPLACED", "parent", 1);
  ChildOptions options;
  options.environment = {{"SHAPESENSE_CHILD_TEST_REPLACED", "child"},
                         {"SHAPESENSE_CHILD_TEST_ADDED", "-2.5"}};
  ChildProcess child(Shell("echo $SHAPESENSE_CHILD_TEST_KEPT $SHAPESENSE_CHILD_TEST_REPLACED "
                           "$SHAPESENSE_CHILD_TEST_ADDED; env | grep -c SHAPESENSE_CHILD_TEST_"),
                     options);
  EXPECT_EQ(WaitForEnd(child), 0);
  EXPECT_EQ(child.output(), "parent child -2.5\n3\n") << "each variable once";
  unsetenv("SHAPESENSE_CHILD_TEST_KEPT");
  unsetenv("SHAPESENSE_CHILD_TEST_REPLACED");
}

// As systemd passes a socket: fd 3, LISTEN_FDS=1 and LISTEN_PID the child's own pid.
TEST(ChildProcessTest, HandsAListeningSocketAsSystemdWould) {
  const int socket = OpenListeningSocket("127.0.0.1:0");
  ChildOptions options;
  options.listen_socket = socket;
  ChildProcess child(Shell("echo $LISTEN_FDS $LISTEN_PID $$; readlink /proc/self/fd/3 | cut -c1-7"),
                     options);
  EXPECT_EQ(WaitForEnd(child), 0);
  std::istringstream said(child.output());
  std::string fds, listen_pid, pid, fd3;
  said >> fds >> listen_pid >> pid >> fd3;
  EXPECT_EQ(fds, "1");
  EXPECT_EQ(listen_pid, pid) << child.output();
  EXPECT_EQ(fd3, "socket:") << child.output();
  EXPECT_EQ(ListeningAddress(socket).rfind("127.0.0.1:", 0), 0u);
  close(socket);
  EXPECT_THROW(OpenListeningSocket("127.0.0.1"), std::runtime_error);
  EXPECT_THROW(OpenListeningSocket("not-an-address:80"), std::runtime_error);
}

TEST(ChildProcessTest, ExitStatusDoesNotWaitAndDescribesTheEnd) {
  ChildProcess child(Shell("echo up; exec sleep 30"));
  ASSERT_TRUE(child.WaitForLine("up", milliseconds(5000)));
  EXPECT_EQ(child.ExitStatus(), std::nullopt);
  child.Signal(SIGKILL);
  const int status = WaitForEnd(child);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_NE(DescribeExitStatus(status).find("signal 9"), std::string::npos);
  EXPECT_EQ(DescribeExitStatus(2 << 8), "exited with status 2");
  EXPECT_EQ(child.Stop(), status) << "a child that ended keeps its status";
}

TEST(ChildProcessTest, StopReadsTheLastWordsAndKillsWhatDoesNotStop) {
  ChildProcess polite(Shell("trap 'echo bye; exit 0' TERM; echo up; while :; do sleep 0.05; done"));
  ASSERT_TRUE(polite.WaitForLine("up", milliseconds(5000)));
  EXPECT_EQ(polite.ExitStatus(), std::nullopt);
  EXPECT_EQ(polite.Stop(), 0);
  EXPECT_NE(polite.output().find("bye"), std::string::npos);

  ChildProcess stubborn(Shell("trap '' TERM; echo up; while :; do sleep 0.05; done"));
  ASSERT_TRUE(stubborn.WaitForLine("up", milliseconds(5000)));
  EXPECT_EQ(stubborn.Stop(milliseconds(300)), -1);
}

TEST(ChildProcessTest, AChildWritingMoreThanAPipeHoldsEndsWhenRead) {
  ChildProcess child(Shell("head -c 1000000 /dev/zero | tr '\\0' a; echo; echo done"));
  EXPECT_EQ(WaitForEnd(child), 0);
  EXPECT_EQ(child.output().size(), 1000000u + 6u);
  EXPECT_EQ(child.Tail(1), "done");
}

TEST(ChildProcessTest, TailGivesTheLastLines) {
  std::mt19937 random(3);
  for (int trial = 0; trial < 20; ++trial) {
    const int lines = std::uniform_int_distribution<int>(0, 30)(random);
    const int wanted = std::uniform_int_distribution<int>(0, 35)(random);
    std::string script =
        "i=0; while [ $i -lt " + std::to_string(lines) + " ]; do echo line$i; i=$((i+1)); done";
    ChildProcess child(Shell(script));
    ASSERT_EQ(WaitForEnd(child), 0);
    std::string expected;
    for (int i = std::max(0, lines - wanted); i < lines; ++i) {
      if (!expected.empty()) expected += '\n';
      expected += "line" + std::to_string(i);
    }
    EXPECT_EQ(child.Tail(wanted), expected) << lines << " lines, " << wanted << " wanted";
  }
}

TEST(ChildProcessTest, OwnProcessGroup) {
  ChildOptions options;
  options.own_process_group = true;
  ChildProcess child(Shell("echo up; exec sleep 30"), options);
  ASSERT_TRUE(child.WaitForLine("up", milliseconds(5000)));
  EXPECT_EQ(getpgid(child.pid()), child.pid());
  EXPECT_NE(getpgid(child.pid()), getpgrp());
}

TEST(ChildProcessTest, EndsWithTheThreadThatStartedIt) {
  ChildOptions options;
  options.end_with_parent = true;
  std::unique_ptr<ChildProcess> child;
  std::thread starter([&] {
    child = std::make_unique<ChildProcess>(Shell("echo up; exec sleep 30"), options);
    child->WaitForLine("up", milliseconds(5000));
  });
  starter.join();
  const int status = WaitForEnd(*child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << DescribeExitStatus(status);
}

}  // namespace
}  // namespace shapesense
