// fixed/check.h — the two kinds of error the whole project distinguishes.
//
// UserError: a user's mistake (a scene file, a flag, a format that cannot hold the scene,
// a program that does not fit the PE memory). It carries a message that says where and
// what was expected; the program prints it and exits non-zero. Tests catch it.
//
// ZEPHYR_CHECK: a programming error. It prints both sides and aborts.
//
// These live in fixed/ because fixed/ is the bottom of the dependency chain
// (fixed <- bitserial <- hosts) and every room needs them.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

namespace zephyr {

class UserError : public std::runtime_error {
 public:
  explicit UserError(const std::string& message, int exitCode = 1)
      : std::runtime_error(message), exitCode_(exitCode) {}
  int ExitCode() const { return exitCode_; }

 private:
  int exitCode_;
};

[[noreturn]] inline void CheckFailed(const char* file, int line, const std::string& what) {
  std::fprintf(stderr, "%s:%d: internal check failed: %s\n", file, line, what.c_str());
  std::abort();
}

namespace detail {
template <typename A, typename B>
std::string CheckMessage(const char* expr, const A& a, const B& b) {
  std::ostringstream s;
  s << expr << " (" << a << " vs " << b << ")";
  return s.str();
}
}  // namespace detail

}  // namespace zephyr

#define ZEPHYR_CHECK(cond)                                         \
  do {                                                             \
    if (!(cond)) ::zephyr::CheckFailed(__FILE__, __LINE__, #cond); \
  } while (0)
#define ZEPHYR_CHECK_OP(a, op, b)                                                   \
  do {                                                                              \
    const auto& zephyr_a_ = (a);                                                    \
    const auto& zephyr_b_ = (b);                                                    \
    if (!(zephyr_a_ op zephyr_b_))                                                  \
      ::zephyr::CheckFailed(                                                        \
          __FILE__, __LINE__,                                                       \
          ::zephyr::detail::CheckMessage(#a " " #op " " #b, zephyr_a_, zephyr_b_)); \
  } while (0)
#define ZEPHYR_CHECK_EQ(a, b) ZEPHYR_CHECK_OP(a, ==, b)
#define ZEPHYR_CHECK_LE(a, b) ZEPHYR_CHECK_OP(a, <=, b)
#define ZEPHYR_CHECK_LT(a, b) ZEPHYR_CHECK_OP(a, <, b)
#define ZEPHYR_CHECK_GE(a, b) ZEPHYR_CHECK_OP(a, >=, b)
