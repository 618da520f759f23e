// The registry of temporary files in flight (client/io/temporary_files.h): a signal that ends the
// process removes what is registered and nothing else, the process still ends by that signal, a
// signal the process ignores stays ignored, and the writers of file_bytes.h register what they
// stage. The signals are raised inside gtest death-test children (forks), whose files the parent
// checks.
#include "client/io/temporary_files.h"

#include <signal.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "client/io/file_bytes.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"

namespace tetrefine::io {
namespace {

using iotest::ScratchDir;

bool Exists(const std::string& path) { return std::filesystem::exists(path); }

// Temporaries beside `path` in its directory, as file_bytes.cc names them.
int TemporariesBeside(const ScratchDir& dir) {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    n += entry.path().filename().string().find(".tmp.") != std::string::npos;
  }
  return n;
}

// "fast": the child is a fork at the EXPECT_EXIT, so it writes in the parent's scratch directory
// (the "threadsafe" style re-runs the test from its start, with a scratch directory of its own).
class IoTemporaryFilesTest : public ::testing::Test {
 protected:
  void SetUp() override { GTEST_FLAG_SET(death_test_style, "fast"); }
};

TEST_F(IoTemporaryFilesTest, ASignalRemovesTheRegisteredFilesAndStillEndsTheProcessByIt) {
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    SCOPED_TRACE(signal_number);
    ScratchDir dir;
    const std::string registered = dir.File("registered");
    const std::string other = dir.File("other");
    iotest::WriteBytes(registered, "x");
    iotest::WriteBytes(other, "y");
    EXPECT_EXIT(
        {
          RemoveTemporariesOnSignals();
          RegisteredTemporary temporary(registered);
          if (!temporary.registered()) std::_Exit(3);
          ::raise(signal_number);
          std::_Exit(4);  // not reached: the handler ends the process
        },
        ::testing::KilledBySignal(signal_number), "");
    EXPECT_FALSE(Exists(registered));
    EXPECT_TRUE(Exists(other));
  }
}

TEST_F(IoTemporaryFilesTest, AnEndedRegistrationIsNotRemoved) {
  ScratchDir dir;
  const std::string path = dir.File("renamed");
  iotest::WriteBytes(path, "x");
  EXPECT_EXIT(
      {
        RemoveTemporariesOnSignals();
        { RegisteredTemporary temporary(path); }
        ::raise(SIGTERM);
      },
      ::testing::KilledBySignal(SIGTERM), "");
  EXPECT_TRUE(Exists(path));
}

// A signal during a commit (a set of files being renamed into place) waits for its end, then ends
// the process as it would have, removing what is still registered.
TEST_F(IoTemporaryFilesTest, ASignalDuringACommitEndsTheProcessAfterIt) {
  ScratchDir dir;
  const std::string path = dir.File("staged");
  iotest::WriteBytes(path, "x");
  EXPECT_EXIT(
      {
        RemoveTemporariesOnSignals();
        RegisteredTemporary temporary(path);
        {
          CommitWindow outer;
          {
            CommitWindow inner;
            ::raise(SIGTERM);
            ::raise(SIGINT);  // a second one is held too; the first is the one that ends it
          }
          if (!Exists(path)) std::_Exit(3);  // still here: nothing ran yet
        }
        std::_Exit(4);  // not reached: the outer window's end ends the process
      },
      ::testing::KilledBySignal(SIGTERM), "");
  EXPECT_FALSE(Exists(path));
}

// nohup starts a program with SIGHUP ignored: the handlers must leave that as it is, so the
// process goes on (and the file stays: nothing ended the process).
TEST_F(IoTemporaryFilesTest, ASignalTheProcessIgnoresStaysIgnored) {
  ScratchDir dir;
  const std::string path = dir.File("kept");
  iotest::WriteBytes(path, "x");
  EXPECT_EXIT(
      {
        ::signal(SIGHUP, SIG_IGN);
        RemoveTemporariesOnSignals();
        RegisteredTemporary temporary(path);
        ::raise(SIGHUP);
        std::_Exit(0);
      },
      ::testing::ExitedWithCode(0), "");
  EXPECT_TRUE(Exists(path));
}

// StagedFiles keeps its temporaries until Commit: each is registered, and a signal before the
// commit removes them (the destination is never created). After a commit or a plain atomic write
// nothing stays registered.
TEST_F(IoTemporaryFilesTest, StagedFilesRegisterTheirTemporariesUntilCommitted) {
  ScratchDir dir;
  const std::string a = dir.File("a.vtu"), b = dir.File("b.vtu");
  EXPECT_EXIT(
      {
        RemoveTemporariesOnSignals();
        StagedFiles staged;
        if (!staged.Write(a, "first").ok() || !staged.Write(b, "second").ok()) std::_Exit(3);
        if (RegisteredTemporaryCountForTesting() != 2) std::_Exit(5);
        ::raise(SIGTERM);
        std::_Exit(4);
      },
      ::testing::KilledBySignal(SIGTERM), "");
  EXPECT_EQ(TemporariesBeside(dir), 0);
  EXPECT_FALSE(Exists(a));
  EXPECT_FALSE(Exists(b));

  const int before = RegisteredTemporaryCountForTesting();
  {
    StagedFiles staged;
    ASSERT_TRUE(staged.Write(a, "first").ok());
    EXPECT_EQ(RegisteredTemporaryCountForTesting(), before + 1);
    ASSERT_TRUE(staged.Commit().ok());
    EXPECT_EQ(RegisteredTemporaryCountForTesting(), before);
  }
  ASSERT_TRUE(WriteFileAtomically(b, "second").ok());
  EXPECT_EQ(RegisteredTemporaryCountForTesting(), before);
  EXPECT_EQ(iotest::ReadBytes(a), "first");
  EXPECT_EQ(iotest::ReadBytes(b), "second");
  EXPECT_EQ(TemporariesBeside(dir), 0);
}

TEST_F(IoTemporaryFilesTest, ARegistryFullOrAPathTooLongStillWrites) {
  ScratchDir dir;
  std::vector<RegisteredTemporary> held;
  for (int i = 0; i < 300; ++i) held.emplace_back(dir.File("slot" + std::to_string(i)));
  int registered = 0;
  for (const RegisteredTemporary& r : held) registered += r.registered();
  EXPECT_EQ(registered, 256);
  EXPECT_FALSE(RegisteredTemporary(std::string(5000, 'x')).registered());
  ASSERT_TRUE(WriteFileAtomically(dir.File("still.vtu"), "written").ok());
  EXPECT_EQ(iotest::ReadBytes(dir.File("still.vtu")), "written");
  held.clear();
  EXPECT_EQ(RegisteredTemporaryCountForTesting(), 0);
}

}  // namespace
}  // namespace tetrefine::io
