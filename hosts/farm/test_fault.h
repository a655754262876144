// hosts/farm/test_fault.h — test-only fault injection for the farm's children, so the tests
// can kill, hang or corrupt a real child process under mpirun (tests/farm/mpi_launch.h).
//
// ZEPHYR_TEST_FAULT="what:rank:n" (passed with `mpirun -x`) makes child `rank`, on receiving
// its (n+1)-th frame, "kill" itself with SIGKILL, "hang" (sleep for an hour), answer with
// "garbage" (a 3-byte result) instead of the frame, or "fail": send the farm protocol's own
// failure message ("injected failure (ZEPHYR_TEST_FAULT)"), as a child whose frame raised a
// UserError does. Unset, nothing happens.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace zephyr::farm {

class TestFault {
 public:
  // The fault the environment asks for, if any; UserError when ZEPHYR_TEST_FAULT is malformed.
  static std::optional<TestFault> FromEnvironment();
  // Called by child `rank` before it renders a frame, after `framesDone` frames: kills or
  // hangs the process when the fault strikes there; true when it should send garbage instead.
  bool StrikeSendsGarbage(int rank, std::uint64_t framesDone) const;
  // True when child `rank`, after `framesDone` frames, should send its failure message.
  bool StrikeFails(int rank, std::uint64_t framesDone) const {
    return what_ == "fail" && rank == rank_ && framesDone == std::uint64_t(afterFrames_);
  }

 private:
  std::string what_;
  int rank_ = -1, afterFrames_ = 0;
};

}  // namespace zephyr::farm
