// cli::InterruptGuard: the first signal is recorded and the command goes on; the next, whichever
// of SIGINT, SIGTERM and SIGHUP it is, ends the process at once and removes the temporaries; a
// signal ignored at start stays ignored; the handlers before the guard are back after it. Each
// case runs in a gtest death-test child (a fork: it writes in the parent's scratch directory).
#include "client/cli/interrupt_guard.h"

#include <signal.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "client/io/temporary_files.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"

namespace tetrefine::cli {
namespace {

using io::iotest::ScratchDir;

class CliInterruptGuardTest : public ::testing::Test {
 protected:
  void SetUp() override { GTEST_FLAG_SET(death_test_style, "fast"); }
};

TEST_F(CliInterruptGuardTest, TheFirstSignalIsRecordedAndAnyNextOneEndsTheProcess) {
  for (const auto& [first, second] : {std::pair{SIGHUP, SIGINT}, std::pair{SIGINT, SIGTERM},
                                      std::pair{SIGTERM, SIGTERM}, std::pair{SIGTERM, SIGHUP}}) {
    SCOPED_TRACE(::testing::Message() << first << " then " << second);
    ScratchDir dir;
    const std::string temporary = dir.File(".out.vtu.tmp");
    io::iotest::WriteBytes(temporary, "half a file");
    EXPECT_EXIT(
        {
          io::RemoveTemporariesOnSignals();
          io::RegisteredTemporary registered(temporary);
          InterruptGuard guard;
          ::raise(first);
          // Recorded, the process goes on (the command would finish its write, then stop).
          if (InterruptGuard::Interrupted() != first) std::_Exit(3);
          ::raise(second);
          std::_Exit(4);  // not reached
        },
        ::testing::KilledBySignal(second), "");
    EXPECT_FALSE(std::filesystem::exists(temporary));
  }
}

// Two signals arriving together (both pending while a long system call ran) are taken one after
// the other: the first recorded, the second ending the process.
TEST_F(CliInterruptGuardTest, TwoSignalsPendingTogetherStillEndTheProcess) {
  EXPECT_EXIT(
      {
        InterruptGuard guard;
        sigset_t both;
        sigset_t previous;
        sigemptyset(&both);
        sigaddset(&both, SIGHUP);
        sigaddset(&both, SIGTERM);
        pthread_sigmask(SIG_BLOCK, &both, &previous);
        ::raise(SIGTERM);
        ::raise(SIGHUP);
        pthread_sigmask(SIG_SETMASK, &previous, nullptr);  // SIGHUP (1) is delivered first
        std::_Exit(4);
      },
      ::testing::KilledBySignal(SIGTERM), "");
}

TEST_F(CliInterruptGuardTest, ASignalIgnoredAtStartStaysIgnored) {
  EXPECT_EXIT(
      {
        ::signal(SIGHUP, SIG_IGN);
        InterruptGuard guard;
        ::raise(SIGHUP);
        ::raise(SIGHUP);
        std::_Exit(InterruptGuard::Interrupted() == 0 ? 0 : 3);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST_F(CliInterruptGuardTest, TheHandlersBeforeTheGuardAreBackAfterIt) {
  ScratchDir dir;
  const std::string temporary = dir.File(".out.vtu.tmp");
  io::iotest::WriteBytes(temporary, "half a file");
  EXPECT_EXIT(
      {
        io::RemoveTemporariesOnSignals();
        io::RegisteredTemporary registered(temporary);
        { InterruptGuard guard; }
        ::raise(SIGINT);  // main's handler: removes the temporary, ends the process
        std::_Exit(4);
      },
      ::testing::KilledBySignal(SIGINT), "");
  EXPECT_FALSE(std::filesystem::exists(temporary));
  EXPECT_EQ(InterruptGuard::InterruptedBy(), "");
}

}  // namespace
}  // namespace tetrefine::cli
