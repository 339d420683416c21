#include <meltlab/core/error.h>
#include <meltlab/core/process.h>

#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <unistd.h>
#include <sstream>

#include "test_files.h"

namespace meltlab {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The program alone: inherited streams and environment, looked up in PATH.
ProcessStatus run_argv(std::vector<std::string> argv) {
  ProcessSpec spec;
  spec.argv = std::move(argv);
  return run_process(spec);
}

class ProcessTest : public ::testing::Test {
 protected:
  test::TempFolder folder_;
  const fs::path dir_ = folder_.path();
};

TEST_F(ProcessTest, ReturnsTheExitStatus) {
  EXPECT_EQ(run_argv({"sh", "-c", "exit 0"}).exit_code, 0);
  const ProcessStatus s = run_argv({"sh", "-c", "exit 7"});
  EXPECT_EQ(s.exit_code, 7);
  EXPECT_EQ(s.signal, 0);
  EXPECT_EQ(s.shell_status(), 7);
  EXPECT_FALSE(s.exited_ok());
}

TEST_F(ProcessTest, ReportsTheSignalThatEndedTheChild) {
  const ProcessStatus s = run_argv({"sh", "-c", "kill -TERM $$"});
  EXPECT_EQ(s.signal, SIGTERM);
  EXPECT_EQ(s.exit_code, -1);
  EXPECT_EQ(s.shell_status(), 128 + SIGTERM);
}

TEST_F(ProcessTest, ArgumentsReachTheChildUnparsed) {
  ProcessSpec spec;
  // No shell between us and printf: the quote, the $ and the blank arrive as given.
  spec.argv = {"printf", "%s|%s", "a b", "'$HOME\""};
  spec.stdout_file = dir_ / "out.txt";
  ASSERT_TRUE(run_process(spec).exited_ok());
  EXPECT_EQ(slurp(dir_ / "out.txt"), "a b|'$HOME\"");
}

TEST_F(ProcessTest, RedirectsEachStreamToItsFile) {
  std::ofstream(dir_ / "in.txt") << "from stdin\n";
  std::ofstream(dir_ / "out.txt") << "old content that must be truncated away\n";
  ProcessSpec spec;
  spec.argv = {"sh", "-c", "cat; echo to-stderr >&2"};
  spec.stdin_file = dir_ / "in.txt";
  spec.stdout_file = dir_ / "out.txt";
  spec.stderr_file = dir_ / "err.txt";
  ASSERT_TRUE(run_process(spec).exited_ok());
  EXPECT_EQ(slurp(dir_ / "out.txt"), "from stdin\n");
  EXPECT_EQ(slurp(dir_ / "err.txt"), "to-stderr\n");
}

TEST_F(ProcessTest, NullDeviceGivesAnEmptyStdin) {
  ProcessSpec spec;
  spec.argv = {"sh", "-c", "wc -c"};
  spec.stdin_file = kNullDevice;
  spec.stdout_file = dir_ / "count.txt";
  ASSERT_TRUE(run_process(spec).exited_ok());
  EXPECT_EQ(std::stoi(slurp(dir_ / "count.txt")), 0);
}

TEST_F(ProcessTest, EnvironmentAdditionsExtendAndReplace) {
  ::setenv("MELTLAB_PROCESS_TEST_KEPT", "kept", 1);
  ::setenv("MELTLAB_PROCESS_TEST_REPLACED", "old", 1);
  ProcessSpec spec;
  spec.argv = {"sh", "-c",
               "printf '%s,%s,%s' \"$MELTLAB_PROCESS_TEST_KEPT\" \"$MELTLAB_PROCESS_TEST_REPLACED\" "
               "\"$MELTLAB_PROCESS_TEST_ADDED\"; env | grep -c '^MELTLAB_PROCESS_TEST_REPLACED=' >&2"};
  spec.env_additions = {{"MELTLAB_PROCESS_TEST_REPLACED", "new"}, {"MELTLAB_PROCESS_TEST_ADDED", "added"}};
  spec.stdout_file = dir_ / "out.txt";
  spec.stderr_file = dir_ / "err.txt";
  ASSERT_TRUE(run_process(spec).exited_ok());
  EXPECT_EQ(slurp(dir_ / "out.txt"), "kept,new,added");
  EXPECT_EQ(slurp(dir_ / "err.txt"), "1\n") << "the replaced variable must appear once";
}

TEST_F(ProcessTest, AProgramThatCannotStartIsAnInputErrorNamingIt) {
  try {
    run_argv({"meltlab-no-such-program-xyz"});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "cannot start 'meltlab-no-such-program-xyz': No such file or directory");
  }
}

TEST_F(ProcessTest, WithoutPathSearchABareNameIsNotFound) {
  ProcessSpec spec;
  spec.argv = {"sh", "-c", "exit 0"};
  spec.search_path = false;  // "sh" relative to the working folder, which has none
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  EXPECT_THROW(run_process(spec), InputError);
  fs::current_path(cwd);
}

TEST_F(ProcessTest, AnUnopenableRedirectionNamesTheFileNotTheProgram) {
  ProcessSpec spec;
  spec.argv = {"true"};
  spec.stderr_file = dir_ / "no-such-folder" / "err.txt";
  try {
    run_process(spec);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir_ / "no-such-folder" / "err.txt").string()), std::string::npos) << what;
    EXPECT_NE(what.find("stderr"), std::string::npos) << what;
    EXPECT_EQ(what.find("cannot start"), std::string::npos) << what;
  }
}

TEST_F(ProcessTest, WaitingSurvivesSignalsDeliveredToTheParent) {
  // A handler without SA_RESTART makes waitpid fail with EINTR; the wait must carry on.
  struct sigaction action {
  }, previous{};
  action.sa_handler = [](int) {};
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  ASSERT_EQ(::sigaction(SIGALRM, &action, &previous), 0);
  ::alarm(1);
  const ProcessStatus s = run_argv({"sh", "-c", "sleep 2; exit 3"});
  ::sigaction(SIGALRM, &previous, nullptr);
  EXPECT_EQ(s.exit_code, 3);
}

}  // namespace
}  // namespace meltlab
