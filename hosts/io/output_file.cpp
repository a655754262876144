#include "hosts/io/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <mutex>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <vector>

#include "fixed/check.h"
#include "hosts/io/test_seam.h"

namespace zephyr {

namespace {

std::string DirectoryOf(const std::string& path) {
  const std::string dir = std::filesystem::path(path).parent_path().string();
  return dir.empty() ? "." : dir;
}

// mkstemp in `path`'s directory; returns the descriptor (or -1 with errno) and the name.
int MakeTemporary(const std::string& path, std::string& name) {
  const std::filesystem::path p(path);
  const std::string pattern =
      (std::filesystem::path(DirectoryOf(path)) / ("." + p.filename().string() + ".tmp-XXXXXX"))
          .string();
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  const int fd = ::mkostemp(buffer.data(), O_CLOEXEC);
  name = buffer.data();
  return fd;
}

// ---- Temporaries removed on SIGINT, SIGTERM and SIGHUP ---------------------------------------
// The live temporaries' names in fixed slots (a signal handler may not allocate or lock): the
// handler unlinks each, restores the default action and raises the signal again, so the
// process ends as it would have, minus the temporary.
constexpr int kSlots = 64;
constexpr size_t kSlotBytes = 4096;
char g_slotPath[kSlots][kSlotBytes];
std::atomic<bool> g_slotUsed[kSlots];

extern "C" void RemoveTemporariesAndReraise(int sig) {
  for (int i = 0; i < kSlots; ++i)
    if (g_slotUsed[i].load(std::memory_order_acquire)) ::unlink(g_slotPath[i]);
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

void InstallSignalCleanup() {
  static const bool installed = [] {
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction old {};
      ::sigaction(sig, nullptr, &old);
      // A signal the process ignores (nohup's SIGHUP) stays ignored.
      if (old.sa_handler == SIG_IGN) continue;
      struct sigaction a {};
      a.sa_handler = RemoveTemporariesAndReraise;
      sigemptyset(&a.sa_mask);
      ::sigaction(sig, &a, nullptr);
    }
    return true;
  }();
  (void)installed;
}

// The slot that now holds `name` (-1 when every slot is taken or the name is too long: the
// temporary is then only removed by the next writer of that output, below).
int Register(const std::string& name) {
  InstallSignalCleanup();
  if (name.size() >= kSlotBytes) return -1;
  static std::mutex lock;
  std::lock_guard<std::mutex> guard(lock);
  for (int i = 0; i < kSlots; ++i)
    if (!g_slotUsed[i].load(std::memory_order_relaxed)) {
      std::memcpy(g_slotPath[i], name.c_str(), name.size() + 1);
      g_slotUsed[i].store(true, std::memory_order_release);
      return i;
    }
  return -1;
}
void Unregister(int slot) {
  if (slot >= 0) g_slotUsed[slot].store(false, std::memory_order_release);
}

// A writer's own stale temporaries: `.NAME.tmp-XXXXXX` beside `path` (mkstemp's six
// characters), left by a process killed outright (SIGKILL, a power cut) and unchanged for a
// minute — a live writer of the same name changes its file as it writes. Only that pattern,
// only in the output's own folder.
void RemoveStaleTemporaries(const std::string& path) {
  namespace fs = std::filesystem;
  const std::string prefix = "." + fs::path(path).filename().string() + ".tmp-";
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (fs::directory_iterator it(DirectoryOf(path), ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() != prefix.size() + 6 || name.compare(0, prefix.size(), prefix) != 0) continue;
    if (name.find_first_not_of(
            "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789", prefix.size()) !=
        std::string::npos)
      continue;
    std::error_code e;
    if (!it->is_regular_file(e) || e) continue;
    const auto modified = fs::last_write_time(it->path(), e);
    if (!e && now - modified > std::chrono::minutes(1)) fs::remove(it->path(), e);
  }
}

mode_t CreateMode() {  // what open(…, 0666) would give under the current umask
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return 0666 & ~mask;
}

// What stands at `path` now, as a reason it may not be replaced ("" when it may: nothing,
// or a regular file, or a link to one). stat follows links: a link to /dev/full is a device.
std::string Unreplaceable(const std::string& path) {
  struct stat s;
  if (::stat(path.c_str(), &s) != 0) {
    // A new name (or a dangling link, replaced like one); ENOTDIR (a file on the way) is
    // the directory's fault, said by the directory check.
    if (errno == ENOENT || errno == ENOTDIR) return "";
    return std::string("cannot check it: ") + std::strerror(errno);  // e.g. a symbolic-link loop
  }
  if (S_ISDIR(s.st_mode)) return "is a directory";
  if (!S_ISREG(s.st_mode))
    return "not a regular file (a device, pipe or socket; outputs are written to a temporary file "
           "and renamed into place, which would replace it)";
  return "";
}

}  // namespace

OutputFile::OutputFile(std::string path, std::string what)
    : path_(std::move(path)), what_(std::move(what)) {
  if (path_.empty()) throw UserError("cannot write the " + what_ + ": empty path");
  if (const std::string why = Unreplaceable(path_); !why.empty())
    throw UserError(path_ + ": cannot write the " + what_ + ": " + why);
  RemoveStaleTemporaries(path_);
  const int fd = MakeTemporary(path_, temporary_);
  if (fd < 0)
    throw UserError(path_ + ": cannot create the " + what_ + " (in " + DirectoryOf(path_) +
                    "): " + std::strerror(errno));
  slot_ = Register(temporary_);
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    const int e = errno;
    ::close(fd);
    ::unlink(temporary_.c_str());
    Unregister(slot_);
    throw UserError(path_ + ": cannot create the " + what_ + ": " + std::strerror(e));
  }
}

OutputFile::~OutputFile() {
  if (file_) std::fclose(file_);
  if (!committed_ && !temporary_.empty()) ::unlink(temporary_.c_str());
  Unregister(slot_);
}

void OutputFile::Commit() {
  ZEPHYR_CHECK(file_ != nullptr && !committed_);
  // The order is the durability (docs/distributed.md, "Durability"): the bytes written (the
  // flush), the mode set and fsync'd, the file closed, then renamed over the name, then the
  // directory fsync'd. Each system call goes through hosts/io/test_seam.h (the plain calls
  // unless a test installed others), so the tests see them made.
  const io::CommitCalls& sys = io::Calls();
  const int fd = ::fileno(file_);
  int error = 0;
  errno = 0;
  if (sys.fflush(file_) != 0 || std::ferror(file_)) error = errno ? errno : EIO;
  if (!error && sys.fchmod(fd, CreateMode()) != 0) error = errno;
  if (!error && sys.fsync(fd) != 0) error = errno;
  if (sys.fclose(file_) != 0 && !error) error = errno;
  file_ = nullptr;
  if (!error && sys.rename(temporary_.c_str(), path_.c_str()) != 0) error = errno;
  if (error) {
    ::unlink(temporary_.c_str());
    Unregister(slot_);
    slot_ = -1;
    throw UserError(path_ + ": cannot write the " + what_ + ": " + std::strerror(error) +
                    " (nothing was written under that name)");
  }
  committed_ = true;
  Unregister(slot_);  // the name is the output's now: a signal from here on must leave it
  slot_ = -1;
  // The rename itself is made durable by syncing the directory; a failure here loses
  // nothing that a crash right now would not.
  const int dir = sys.openDirectory(DirectoryOf(path_).c_str());
  if (dir >= 0) {
    sys.fsync(dir);
    sys.close(dir);
  }
}

void WriteOutputFile(const std::string& path, const std::string& what, std::string_view bytes) {
  OutputFile f(path, what);
  std::fwrite(bytes.data(), 1, bytes.size(), f.Stream());
  f.Commit();
}

void CheckOutputPath(const std::string& flag, const std::string& path) {
  if (path.empty())
    throw UserError(flag + ": empty path (give a file name, or leave the flag out)");
  if (const std::string why = Unreplaceable(path); !why.empty())
    throw UserError(flag + " " + path + ": " + why);
  struct stat s;
  const std::string dir = DirectoryOf(path);
  if (::stat(dir.c_str(), &s) != 0)
    throw UserError(flag + " " + path + ": directory " + dir + " does not exist");
  if (!S_ISDIR(s.st_mode)) throw UserError(flag + " " + path + ": " + dir + " is not a directory");
  std::string probe;
  const int fd = MakeTemporary(path, probe);
  if (fd < 0)
    throw UserError(flag + " " + path + ": cannot create a file in " + dir + ": " +
                    std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
}

void CheckOutputs(const std::vector<PlannedOutput>& outputs, const std::vector<RunInput>& inputs) {
  std::vector<const PlannedOutput*> seen;
  for (const PlannedOutput& o : outputs) {
    if (o.path.empty() || o.path == "-") continue;
    for (const RunInput& in : inputs)
      if (!in.path.empty() && SameFile(o.path, in.path))
        throw UserError(o.flag + " " + o.path + ": is " + in.what +
                        " this run reads; choose another name");
    for (const PlannedOutput* earlier : seen)
      if (SameFile(o.path, earlier->path))
        throw UserError(earlier->flag + " and " + o.flag + " name the same file (" + o.path +
                        "); give each output its own name");
    CheckOutputPath(o.flag, o.path);
    seen.push_back(&o);
  }
}

bool SameFile(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  const bool hasA = ::stat(a.c_str(), &sa) == 0, hasB = ::stat(b.c_str(), &sb) == 0;
  if (hasA && hasB) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (hasA != hasB) return false;
  std::error_code ea, eb;
  const auto ca = std::filesystem::weakly_canonical(std::filesystem::absolute(a), ea);
  const auto cb = std::filesystem::weakly_canonical(std::filesystem::absolute(b), eb);
  if (ea || eb) return std::filesystem::absolute(a) == std::filesystem::absolute(b);
  return ca == cb;
}

}  // namespace zephyr
