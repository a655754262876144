// hosts/io/output_file.h — every file zephyr writes (PNG, JSON report, primary dump, CSVs,
// scenes, the frame checkpoint's header) is written atomically, and every output path is
// checked before any work starts (docs/distributed.md, "Durability").
//
//   OutputFile f(path, "PNG file");             // a temporary file beside `path`
//   std::fprintf(f.Stream(), ...);               // write everything
//   f.Commit();                                  // flushed, fsync'd, renamed over `path`
//
// Until Commit succeeds `path` is untouched: an old file of that name stays as it was, and
// no partial file ever carries the name. A failed or abandoned OutputFile removes its
// temporary file, and so does SIGINT, SIGTERM or SIGHUP (a handler installed with the first
// OutputFile removes the live temporaries, then the signal ends the process as before). Only a
// process killed outright (SIGKILL) leaves one behind, named `.NAME.tmp-XXXXXX` in the same
// directory; the next writer of NAME removes such files once they are a minute old.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace zephyr {

class OutputFile {
 public:
  // Creates the temporary file in `path`'s directory. `what` names the file in messages
  // ("PNG file", "report"). UserError when `path` exists and is not a regular file (a device
  // node, a directory, a pipe: renaming over it would replace it) or when the temporary
  // cannot be created (missing directory, no permission, read-only or full file system).
  OutputFile(std::string path, std::string what);
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile();  // removes the temporary file unless committed

  // The open temporary file (buffered; errors show at Commit).
  std::FILE* Stream() const { return file_; }
  // Flushes, fsyncs and closes the temporary file, then renames it over `path` (mode
  // 0666 & ~umask, as a plain create would give). UserError naming `path`, `what` and the
  // system's reason (e.g. "No space left on device") on any failure; `path` is then unchanged.
  void Commit();

 private:
  std::string path_, what_, temporary_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
  int slot_ = -1;  // its place among the temporaries a signal removes (-1: none)
};

// Writes `bytes` to `path` atomically (one OutputFile).
void WriteOutputFile(const std::string& path, const std::string& what, std::string_view bytes);

// Checks, before any work, that `path` can be written by `flag` (e.g. "--out"): not empty,
// not an existing directory or device or anything but a regular file, and its directory
// exists and takes a new file (tried by creating and removing a temporary file there).
// UserError "flag PATH: reason" otherwise.
void CheckOutputPath(const std::string& flag, const std::string& path);

// One file a run will write: the flag that names it ("--out") and its path.
struct PlannedOutput {
  std::string flag, path;
};
// One file the same run reads: what it is ("the scene file") and its path.
struct RunInput {
  std::string what, path;
};

// The pre-flight every command that writes files runs before any work: each output through
// CheckOutputPath (so a device node, a directory or a missing directory is refused, never
// replaced), none the same file as an input of the run or as another output. Outputs with
// an empty path or "-" (standard output) are skipped. UserError naming the flag otherwise.
void CheckOutputs(const std::vector<PlannedOutput>& outputs,
                  const std::vector<RunInput>& inputs = {});

// True when `a` and `b` name the same file: the same inode when both exist, else the same
// absolute path after resolving the directories' symbolic links and `..`.
bool SameFile(const std::string& a, const std::string& b);

}  // namespace zephyr
