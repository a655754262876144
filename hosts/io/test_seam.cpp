#include "hosts/io/test_seam.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <memory>

#include "fixed/check.h"

namespace zephyr::io {

namespace {

constexpr const char* kNames[kCommitSteps] = {"fflush", "fchmod",   "fsync",     "fclose",
                                              "rename", "open-dir", "fsync-dir", "close-dir"};

// SystemCalls() wrapped so that the process kills itself just before `step` of its
// `file`-th commit (files counted by their fflush).
CommitCalls KillingCalls(CommitStep step, int file) {
  CommitCalls plain = SystemCalls(), c = plain;
  auto files = std::make_shared<int>(0);
  auto before = [=](CommitStep s) {
    if (s == step && *files == file) ::raise(SIGKILL);
  };
  c.fflush = [=](std::FILE* f) {
    ++*files, before(CommitStep::kFlush);
    return plain.fflush(f);
  };
  c.fchmod = [=](int fd, mode_t m) {
    before(CommitStep::kChmod);
    return plain.fchmod(fd, m);
  };
  c.fsync = [=](int fd) {
    struct stat s;
    const bool directory = ::fstat(fd, &s) == 0 && S_ISDIR(s.st_mode);
    before(directory ? CommitStep::kSyncDirectory : CommitStep::kSync);
    return plain.fsync(fd);
  };
  c.fclose = [=](std::FILE* f) {
    before(CommitStep::kClose);
    return plain.fclose(f);
  };
  c.rename = [=](const char* a, const char* b) {
    before(CommitStep::kRename);
    return plain.rename(a, b);
  };
  c.openDirectory = [=](const char* d) {
    before(CommitStep::kOpenDirectory);
    return plain.openDirectory(d);
  };
  c.close = [=](int fd) {
    before(CommitStep::kCloseDirectory);
    return plain.close(fd);
  };
  return c;
}

CommitCalls& Installed() {
  static CommitCalls calls = [] {
    const char* spec = std::getenv("ZEPHYR_TEST_IO_KILL");
    if (!spec) return SystemCalls();
    const std::string text = spec, name = text.substr(0, text.find(':'));
    const std::optional<CommitStep> step = CommitStepNamed(name);
    int file = 1;
    char rest = 0;
    if (!step ||
        (name.size() < text.size() &&
         (std::sscanf(text.c_str() + name.size(), ":%d%c", &file, &rest) != 1 || file < 1)))
      throw UserError(
          "ZEPHYR_TEST_IO_KILL: expected step[:n] (fflush, fchmod, fsync, fclose, "
          "rename, open-dir, fsync-dir or close-dir; n >= 1), got '" +
          text + "'");
    return KillingCalls(*step, file);
  }();
  return calls;
}

}  // namespace

const char* CommitStepName(CommitStep step) { return kNames[int(step)]; }

std::optional<CommitStep> CommitStepNamed(const std::string& name) {
  for (int i = 0; i < kCommitSteps; ++i)
    if (name == kNames[i]) return CommitStep(i);
  return std::nullopt;
}

CommitCalls SystemCalls() {
  CommitCalls c;
  c.fflush = [](std::FILE* f) { return std::fflush(f); };
  c.fchmod = [](int fd, mode_t m) { return ::fchmod(fd, m); };
  c.fsync = [](int fd) { return ::fsync(fd); };
  c.fclose = [](std::FILE* f) { return std::fclose(f); };
  c.rename = [](const char* a, const char* b) { return ::rename(a, b); };
  c.openDirectory = [](const char* d) { return ::open(d, O_RDONLY | O_DIRECTORY | O_CLOEXEC); };
  c.close = [](int fd) { return ::close(fd); };
  return c;
}

const CommitCalls& Calls() { return Installed(); }

CommitCalls SetCommitCalls(CommitCalls calls) {
  CommitCalls previous = std::move(Installed());
  Installed() = std::move(calls);
  return previous;
}

}  // namespace zephyr::io
