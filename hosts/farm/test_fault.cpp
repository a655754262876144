#include "hosts/farm/test_fault.h"

#include <signal.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "fixed/check.h"

namespace zephyr::farm {

std::optional<TestFault> TestFault::FromEnvironment() {
  const char* spec = std::getenv("ZEPHYR_TEST_FAULT");
  if (!spec) return std::nullopt;
  TestFault fault;
  char what[16] = {};
  if (std::sscanf(spec, "%15[a-z]:%d:%d", what, &fault.rank_, &fault.afterFrames_) != 3)
    throw UserError(std::string("ZEPHYR_TEST_FAULT: expected what:rank:frames, got ") + spec);
  fault.what_ = what;
  if (fault.what_ != "kill" && fault.what_ != "hang" && fault.what_ != "garbage" &&
      fault.what_ != "fail")
    throw UserError("ZEPHYR_TEST_FAULT: unknown fault '" + fault.what_ + "'");
  return fault;
}

bool TestFault::StrikeSendsGarbage(int rank, std::uint64_t framesDone) const {
  if (rank != rank_ || framesDone != std::uint64_t(afterFrames_)) return false;
  if (what_ == "kill") ::raise(SIGKILL);
  if (what_ == "hang") std::this_thread::sleep_for(std::chrono::hours(1));
  return what_ == "garbage";
}

}  // namespace zephyr::farm
