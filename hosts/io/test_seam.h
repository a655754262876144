// hosts/io/test_seam.h — test-only seam: the system calls OutputFile::Commit makes, as
// functions a test may replace, so that it can see each call as it is made (their order, and
// what the disk holds at each), fail any one of them, or kill the process just before one
// (tests/io/output_file_test.cpp; docs/distributed.md, "Durability"). A crash between two
// calls cannot be staged in a unit test; their order can be checked, and a process killed at
// each shows what a crash there leaves.
//
// By default (always in production) they are the plain calls. A test installs others with
// SetCommitCalls; ZEPHYR_TEST_IO_KILL="step[:n]" (a CommitStepName; n the n-th file this
// process commits, from 1, default 1) makes the process SIGKILL itself just before that step.
#pragma once

#include <sys/types.h>

#include <cstdio>
#include <functional>
#include <optional>
#include <string>

namespace zephyr::io {

// Commit's steps, in the order it makes them.
enum class CommitStep : int {
  kFlush,           // fflush: the buffered bytes written to the temporary (write(2))
  kChmod,           // fchmod: the mode a plain create would give (0666 & ~umask)
  kSync,            // fsync of the temporary
  kClose,           // fclose of the temporary (it is closed even when this fails)
  kRename,          // rename of the temporary over the output's name
  kOpenDirectory,   // open of the output's directory
  kSyncDirectory,   // fsync of the directory: the rename made durable
  kCloseDirectory,  // close of the directory
};
inline constexpr int kCommitSteps = 8;
// "fflush", "fchmod", "fsync", "fclose", "rename", "open-dir", "fsync-dir", "close-dir".
const char* CommitStepName(CommitStep step);
std::optional<CommitStep> CommitStepNamed(const std::string& name);

// The calls themselves (fsync serves both kSync and kSyncDirectory; close is the directory's).
struct CommitCalls {
  std::function<int(std::FILE*)> fflush;
  std::function<int(int, mode_t)> fchmod;
  std::function<int(int)> fsync;
  std::function<int(std::FILE*)> fclose;
  std::function<int(const char*, const char*)> rename;
  std::function<int(const char*)> openDirectory;  // a descriptor, or -1 with errno
  std::function<int(int)> close;
};

CommitCalls SystemCalls();  // the plain calls (open with O_RDONLY | O_DIRECTORY | O_CLOEXEC)
// What Commit calls: SystemCalls(), or what ZEPHYR_TEST_IO_KILL or SetCommitCalls installed.
// UserError when ZEPHYR_TEST_IO_KILL is malformed.
const CommitCalls& Calls();
// Installs `calls` for this process and returns the ones they replace. Not synchronised:
// tests install them while no other thread commits a file.
CommitCalls SetCommitCalls(CommitCalls calls);

}  // namespace zephyr::io
