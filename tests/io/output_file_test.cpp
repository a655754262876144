// Atomic output files (hosts/io/output_file.h): a committed file appears whole; an abandoned
// or failed one leaves the old file of that name untouched and no temporary behind — on a
// real full disk (a tiny tmpfs) too; output paths that cannot work are refused up front.
// Durability as an ordering: Commit's system calls traced as they are made (hosts/io/test_seam.h)
// — write (the flush), mode, fsync, close, rename, the directory's fsync — with what each
// finds on disk; each failed in turn; the process killed before each.
#include "hosts/io/output_file.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "fixed/check.h"
#include "hosts/io/test_seam.h"
#include "hosts/trace/image.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr {
namespace {

using testing::ReadFile;

int FilesIn(const std::string& dir) {
  int n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

TEST(OutputFile, AppearsOnlyWhenCommitted) {
  testing::TempDir dir;
  const std::string path = dir / "a.txt";
  std::ofstream(path) << "old";
  {
    OutputFile f(path, "text");
    std::fputs("new contents", f.Stream());
    EXPECT_EQ(ReadFile(path), "old") << "replaced before Commit";
    EXPECT_EQ(FilesIn(dir / ""), 2) << "the temporary sits beside the file";
  }  // abandoned, as when an exception unwinds
  EXPECT_EQ(ReadFile(path), "old");
  EXPECT_EQ(FilesIn(dir / ""), 1) << "temporary left behind";
  WriteOutputFile(path, "text", "new contents");
  EXPECT_EQ(ReadFile(path), "new contents");
  EXPECT_EQ(FilesIn(dir / ""), 1);
  EXPECT_EQ(std::filesystem::status(path).permissions() & std::filesystem::perms::others_read,
            std::filesystem::perms::others_read)
      << "mode as a plain create gives (0666 & ~umask), not mkstemp's 0600";
}

// A real full disk: the write fails at Commit with the system's reason, the good file of
// that name is intact and no temporary is left.
TEST(OutputFile, AFullDiskKeepsTheOldFileAndLeavesNoTemporary) {
  testing::TinyDisk disk(16 * 1024);
  if (!disk.Mounted()) GTEST_SKIP() << "needs root to mount a tmpfs";
  Image image(64, 64);
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = {(i % 7) / 7.0, 0.5, 0.25};
  const std::string png = disk / "o.png";
  WritePng(png, image);
  const std::string good = ReadFile(png);
  ASSERT_FALSE(good.empty());
  testing::FillDisk(disk);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = {(i % 13) / 13.0, 1, 0};
  try {
    WritePng(png, image);
    FAIL() << "wrote a PNG on a full disk";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadFile(png), good) << "the old image was damaged";
  EXPECT_EQ(FilesIn(disk / ""), 2) << "o.png and the filler only";
  EXPECT_THROW(WriteOutputFile(disk / "r.json", "report", std::string(8192, 'x')), UserError);
  EXPECT_FALSE(std::filesystem::exists(disk / "r.json"));
  std::filesystem::remove(disk / "filler");
  WritePng(png, image);  // room again: the new image replaces the old
  EXPECT_NE(ReadFile(png), good);
  EXPECT_EQ(FilesIn(disk / ""), 1);
}

TEST(OutputFile, PathsThatCannotBeWrittenAreRefusedUpFront) {
  testing::TempDir dir;
  auto refused = [](const std::string& path, const std::string& why) {
    try {
      CheckOutputPath("--out", path);
      ADD_FAILURE() << path << " accepted";
    } catch (const UserError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("--out", 0), 0u) << e.what();
    }
  };
  refused("", "empty path");
  refused(dir / "", "is a directory");
  refused(dir / "missing/o.png", "does not exist");
  refused("/dev/full", "not a regular file");  // a rename would replace the device node
  std::ofstream(dir / "plain") << "x";
  refused(dir / "plain/o.png", "is not a directory");
  EXPECT_NO_THROW(CheckOutputPath("--out", dir / "o.png"));
  EXPECT_NO_THROW(CheckOutputPath("--out", dir / "plain"));  // an existing file is replaced
  EXPECT_EQ(FilesIn(dir / ""), 1) << "the probe file was left behind";
}

TEST(OutputFile, SameFileSeesThroughSpellingsAndLinks) {
  testing::TempDir dir;
  std::ofstream(dir / "s.nff") << "x";
  std::filesystem::create_directory(dir / "sub");
  std::filesystem::create_symlink(dir / "s.nff", dir / "link.nff");
  EXPECT_TRUE(SameFile(dir / "s.nff", dir / "sub/../s.nff"));
  EXPECT_TRUE(SameFile(dir / "s.nff", dir / "link.nff"));
  EXPECT_TRUE(SameFile(dir / "new.png", dir / "sub/../new.png"));  // neither exists yet
  EXPECT_FALSE(SameFile(dir / "s.nff", dir / "new.png"));
  EXPECT_FALSE(SameFile(dir / "a.png", dir / "b.png"));
}

// ---- Durability as an ordering --------------------------------------------

using io::CommitStep;

// The temporaries beside `path` (.NAME.tmp-XXXXXX).
std::vector<std::string> Temporaries(const std::string& path) {
  std::vector<std::string> found;
  const std::string prefix = "." + std::filesystem::path(path).filename().string() + ".tmp-";
  for (const auto& e :
       std::filesystem::directory_iterator(std::filesystem::path(path).parent_path()))
    if (e.path().filename().string().rfind(prefix, 0) == 0) found.push_back(e.path().string());
  return found;
}

off_t SizeOf(int fd) {
  struct stat s;
  return ::fstat(fd, &s) == 0 ? s.st_size : -1;
}

// The system calls with `around` put around each: it gets the step, the descriptor it acts
// on (-1 for rename and the directory's open) and the call, and returns what the call would.
using Around = std::function<int(CommitStep step, int fd, const std::function<int()>& call)>;

io::CommitCalls Wrapped(Around around) {
  const io::CommitCalls plain = io::SystemCalls();
  io::CommitCalls c;
  c.fflush = [=](std::FILE* f) {
    return around(CommitStep::kFlush, ::fileno(f), [&] { return plain.fflush(f); });
  };
  c.fchmod = [=](int fd, mode_t m) {
    return around(CommitStep::kChmod, fd, [&] { return plain.fchmod(fd, m); });
  };
  c.fsync = [=](int fd) {
    struct stat s;
    const bool directory = ::fstat(fd, &s) == 0 && S_ISDIR(s.st_mode);
    return around(directory ? CommitStep::kSyncDirectory : CommitStep::kSync, fd,
                  [&] { return plain.fsync(fd); });
  };
  c.fclose = [=](std::FILE* f) {
    return around(CommitStep::kClose, ::fileno(f), [&] { return plain.fclose(f); });
  };
  c.rename = [=](const char* a, const char* b) {
    return around(CommitStep::kRename, -1, [&] { return plain.rename(a, b); });
  };
  c.openDirectory = [=](const char* d) {
    return around(CommitStep::kOpenDirectory, -1, [&] { return plain.openDirectory(d); });
  };
  c.close = [=](int fd) {
    return around(CommitStep::kCloseDirectory, fd, [&] { return plain.close(fd); });
  };
  return c;
}

// Wrapped calls for the test's lifetime.
struct ScopedSeam {
  explicit ScopedSeam(Around around) : previous(io::SetCommitCalls(Wrapped(std::move(around)))) {}
  ~ScopedSeam() { io::SetCommitCalls(std::move(previous)); }
  io::CommitCalls previous;
};

// Every call Commit makes, in order, with what the disk holds just before and after it: the
// bytes reach the temporary at the flush (or before, for more than a buffer), all of them
// before the fsync; the fsync before the close; the rename only of the closed, synced, whole
// temporary with its final mode, the old file intact until then; the directory's fsync after
// the rename, on the output's own directory. A small file and one larger than stdio's buffer.
TEST(OutputFile, CommitWritesFlushesSyncsClosesRenamesThenSyncsTheDirectory) {
  for (const std::size_t bytes : {std::size_t(100), (std::size_t(1) << 20) + 100}) {
    testing::TempDir dir;
    const std::string path = dir / "out.bin";
    std::ofstream(path) << "old";
    const std::string contents(bytes, 'n');
    std::vector<std::string> calls;
    int fileFd = -1;
    ScopedSeam seam([&](CommitStep step, int fd, const std::function<int()>& call) {
      calls.push_back(io::CommitStepName(step));
      const std::vector<std::string> temporaries = Temporaries(path);
      const std::string what = std::to_string(bytes) + " bytes, before " + io::CommitStepName(step);
      switch (step) {
        case CommitStep::kFlush:
          fileFd = fd;
          EXPECT_LT(SizeOf(fd), off_t(bytes)) << what << ": the stream writes at its flush";
          break;
        case CommitStep::kChmod:
        case CommitStep::kSync:
          EXPECT_EQ(SizeOf(fd), off_t(bytes)) << what << ": every byte written first";
          break;
        case CommitStep::kClose:
          EXPECT_EQ(calls[calls.size() - 2], "fsync") << what;
          break;
        case CommitStep::kRename: {
          EXPECT_EQ(::fcntl(fileFd, F_GETFD), -1) << what << ": the temporary is closed";
          EXPECT_EQ(errno, EBADF) << what;
          EXPECT_EQ(testing::ReadFile(path), "old") << what;
          EXPECT_EQ(temporaries.size(), 1u) << what;
          if (temporaries.size() == 1) {
            EXPECT_EQ(testing::ReadFile(temporaries[0]), contents) << what;
            const mode_t mask = ::umask(0);
            ::umask(mask);
            EXPECT_EQ(std::filesystem::status(temporaries[0]).permissions(),
                      std::filesystem::perms(0666 & ~mask))
                << what;
          }
          break;
        }
        case CommitStep::kOpenDirectory:
          EXPECT_EQ(testing::ReadFile(path), contents) << what << ": renamed first";
          EXPECT_TRUE(temporaries.empty()) << what;
          break;
        case CommitStep::kSyncDirectory:
        case CommitStep::kCloseDirectory: {
          struct stat s, d;
          EXPECT_EQ(::fstat(fd, &s), 0) << what;
          EXPECT_EQ(::stat((dir / "").c_str(), &d), 0) << what;
          EXPECT_TRUE(S_ISDIR(s.st_mode) && s.st_ino == d.st_ino && s.st_dev == d.st_dev)
              << what << ": the output's own directory";
          break;
        }
      }
      const int result = call();
      if (step == CommitStep::kFlush) {
        EXPECT_EQ(SizeOf(fd), off_t(bytes)) << what << ", after it";
      }
      return result;
    });
    OutputFile f(path, "file");
    std::fwrite(contents.data(), 1, contents.size(), f.Stream());
    EXPECT_EQ(testing::ReadFile(path), "old");
    f.Commit();
    EXPECT_EQ(calls, (std::vector<std::string>{"fflush", "fchmod", "fsync", "fclose", "rename",
                                               "open-dir", "fsync-dir", "close-dir"}));
    EXPECT_EQ(testing::ReadFile(path), contents);
  }
}

// Each step failed in turn (EIO; a failed fclose still closes): up to the rename, the commit
// fails naming the file and the reason, the old file is intact, no temporary is left and no
// later step runs — nothing is renamed that was not synced; after it, the new file stands
// (a directory that cannot be synced loses nothing a crash would not).
TEST(OutputFile, AFailureAtEveryStepLeavesTheOldFileOrTheWholeNewOne) {
  for (int failing = 0; failing < io::kCommitSteps; ++failing) {
    const CommitStep fail = CommitStep(failing);
    const std::string what = std::string("failing ") + io::CommitStepName(fail);
    testing::TempDir dir;
    const std::string path = dir / "out.bin";
    std::ofstream(path) << "old";
    std::vector<CommitStep> calls;
    ScopedSeam seam([&](CommitStep step, int, const std::function<int()>& call) {
      calls.push_back(step);
      if (step != fail) return call();
      if (step == CommitStep::kClose) call();
      errno = EIO;
      return -1;
    });
    bool threw = false;
    try {
      WriteOutputFile(path, "report", "new contents");
    } catch (const UserError& e) {
      threw = true;
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << what << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(std::strerror(EIO)), std::string::npos)
          << what << ": " << e.what();
    }
    const bool beforeRename = fail <= CommitStep::kRename;
    EXPECT_EQ(threw, beforeRename) << what;
    EXPECT_EQ(testing::ReadFile(path), beforeRename ? "old" : "new contents") << what;
    EXPECT_TRUE(Temporaries(path).empty()) << what;
    // After a failure, only the close (the stream must not leak): nothing unsynced is renamed.
    std::vector<CommitStep> expected;
    for (int s = 0; s < io::kCommitSteps; ++s) {
      const CommitStep step = CommitStep(s);
      const bool runs = beforeRename ? step <= fail || step == CommitStep::kClose
                                     : !(fail == CommitStep::kOpenDirectory && step > fail);
      if (runs) expected.push_back(step);
    }
    EXPECT_EQ(calls, expected) << what;
  }
}

// The process killed (SIGKILL) just before each step, as a crash would stop it: `zephyr gen`
// replacing a scene file leaves the old file whole (before the rename) or the new one whole
// (after it), never a part; only a kill before the rename leaves a temporary, one.
TEST(OutputFile, AProcessKilledBeforeEveryStepLeavesTheOldFileOrTheWholeNewOne) {
  testing::TempDir dir;
  const std::string path = dir / "s.nff", fresh = dir / "fresh.nff";
  const std::string gen = "gen spheres --count 40 --seed 7 --size 64x48 --out ";
  ASSERT_EQ(testing::RunZephyrProcess(gen + fresh).status, 0);
  const std::string wanted = testing::ReadFile(fresh);
  for (int s = 0; s < io::kCommitSteps; ++s) {
    const CommitStep step = CommitStep(s);
    for (const std::string& t : Temporaries(path)) std::filesystem::remove(t);
    std::ofstream(path) << "old";
    const testing::Launch r =
        testing::RunCommand(std::string("ZEPHYR_TEST_IO_KILL=") + io::CommitStepName(step) + " " +
                            testing::ZephyrPath() + " " + gen + path);
    EXPECT_EQ(r.status, 128 + SIGKILL) << io::CommitStepName(step) << ": " << r.output;
    const bool renamed = step > CommitStep::kRename;
    EXPECT_EQ(testing::ReadFile(path), renamed ? wanted : "old")
        << "killed before " << io::CommitStepName(step);
    EXPECT_EQ(Temporaries(path).size(), renamed ? 0u : 1u)
        << "killed before " << io::CommitStepName(step);
  }
  const testing::Launch bad =
      testing::RunCommand("ZEPHYR_TEST_IO_KILL=fsink " + testing::ZephyrPath() + " " + gen + path);
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find("ZEPHYR_TEST_IO_KILL"), std::string::npos) << bad.output;
}

// SIGINT, SIGTERM or SIGHUP while an output is being written removes its temporary and still
// ends the process by that signal (issue 39: `.NAME.tmp-XXXXXX` was left beside the output).
// A signal the process was started ignoring (a background job's SIGINT, nohup's SIGHUP) stays
// ignored: the writer goes on.
TEST(OutputFile, ASignalDuringAWriteLeavesNoTemporary) {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction now {};
    ::sigaction(sig, nullptr, &now);
    const bool ignored = now.sa_handler == SIG_IGN;
    testing::TempDir dir;
    const std::string path = dir / "image.png";
    std::ofstream(path) << "old";
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      OutputFile f(path, "PNG file");
      std::fputs("partial", f.Stream());
      std::fflush(f.Stream());
      ::raise(sig);
      ::_exit(0);  // not reached: the signal ends the process
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    if (ignored) {  // inherited as ignored: raise() did nothing, the child exited by _exit(0)
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << sig << " " << status;
      EXPECT_EQ(testing::ReadFile(path), "old");
      continue;
    }
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << sig << " " << status;
    EXPECT_EQ(Temporaries(path).size(), 0u) << "signal " << sig;
    EXPECT_EQ(testing::ReadFile(path), "old");
  }
}

// A temporary a killed writer left (SIGKILL: no handler runs) is removed by the next writer of
// the same output once it is a minute old; a fresh one (a live writer's) and other files of
// that pattern's neighbours stay.
TEST(OutputFile, TheNextWriterRemovesItsOwnStaleTemporaries) {
  testing::TempDir dir;
  const std::string path = dir / "a.png";
  const std::string stale = dir / ".a.png.tmp-AbC123", fresh = dir / ".a.png.tmp-XyZ789",
                    other = dir / ".b.png.tmp-AbC123", longer = dir / ".a.png.tmp-AbC1234";
  for (const std::string& f : {stale, fresh, other, longer}) std::ofstream(f) << "x";
  const auto old = std::filesystem::file_time_type::clock::now() - std::chrono::minutes(5);
  for (const std::string& f : {stale, other, longer}) std::filesystem::last_write_time(f, old);
  WriteOutputFile(path, "PNG file", "new");
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_TRUE(std::filesystem::exists(fresh));
  EXPECT_TRUE(std::filesystem::exists(other));
  EXPECT_TRUE(std::filesystem::exists(longer));
  EXPECT_EQ(testing::ReadFile(path), "new");
}

}  // namespace
}  // namespace zephyr
