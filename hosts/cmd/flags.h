// hosts/cmd/flags.h — numeric flags, checked when the command line is parsed (before any
// work, on every method), each with one message that says what it expects:
//
//   AddInteger(*cmd, "--depth", o->trace.depth, 1, 64, "Ray-tree depth limit");
//   // zephyr render --depth abc  →  "--depth: expected an integer 1..64, got 'abc'"
//
// CLI11's own conversion messages ("Could not convert", a range printed with 309 digits)
// never reach a user: every numeric flag of every command is declared through these
// (docs/errors.md, "Flags"). The value is read in decimal only ("010" is ten, "0x10" an
// error) and the whole token must be the number.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>

#include "fixed/named.h"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace zephyr {

// Parses `text` as a decimal integer in [lo, hi]. CLI::ValidationError (a parse error,
// printed once as "zephyr: error: FLAG: expected an integer LO..HI, got 'TEXT'") otherwise.
// `why`, when given, follows the message in parentheses (where the range comes from).
int64_t ParseIntegerFlag(const std::string& flag, const std::string& text, int64_t lo, int64_t hi,
                         const std::string& why = "");
uint64_t ParseUnsignedFlag(const std::string& flag, const std::string& text, uint64_t lo,
                           uint64_t hi, const std::string& why = "");
// Parses `text` as a finite decimal number in [lo, hi] (hi may be infinity: no upper end).
double ParseNumberFlag(const std::string& flag, const std::string& text, double lo, double hi);

// Adds `name` to `app`: `set` receives the flag's text (the last one given) and stores the
// parsed value; `typeName` and `defaultText` are what --help shows.
CLI::Option* AddParsedOption(CLI::App& app, const std::string& name,
                             std::function<void(const std::string&)> set,
                             const std::string& typeName, const std::string& defaultText,
                             const std::string& help);

// An integer flag in [lo, hi], any integral type; the help shows the range and the default
// (the value at the time of the call, when it is in the range).
template <class T>
requires std::is_integral_v<T> CLI::Option* AddInteger(CLI::App& app, const std::string& name,
                                                       T& value, T lo, T hi,
                                                       const std::string& help,
                                                       const std::string& why = "") {
  auto set = [&value, name, lo, hi, why](const std::string& text) {
    if constexpr (std::is_signed_v<T>)
      value = T(ParseIntegerFlag(name, text, lo, hi, why));
    else
      value = T(ParseUnsignedFlag(name, text, lo, hi, why));
  };
  // A value outside the range is a "not given" marker (-1: the planner chooses): not shown.
  const bool inRange = value >= lo && value <= hi;
  return AddParsedOption(app, name, set, "INT " + std::to_string(lo) + ".." + std::to_string(hi),
                         inRange ? std::to_string(value) : "", help);
}

// Refuses a flag's text: CLI::ValidationError, printed as "FLAG: expected EXPECTED, got 'TEXT'"
// (the text shown as printable ASCII, at most 40 bytes).
[[noreturn]] void RefuseFlag(const std::string& flag, const std::string& expected,
                             const std::string& text);

// A flag whose value is one of a table's names (fixed/named.h): any other text is refused as
// the command line is parsed ("--precision: expected float or double, got 'x'"); --help
// shows the names and the default (the value at the time of the call).
template <class E, size_t N>
CLI::Option* AddNamed(CLI::App& app, const std::string& name, E& value,
                      const NamedValues<E, N>& names, const std::string& help) {
  auto set = [&value, name, &names](const std::string& text) {
    const std::optional<E> v = names.Find(text);
    if (!v) RefuseFlag(name, names.List(), text);
    value = *v;
  };
  return AddParsedOption(app, name, set, "NAME", names.NameOf(value), help);
}

// No upper end, for AddNumber's `hi`.
inline constexpr double kNoUpperEnd = __builtin_inf();

// A finite number flag in [lo, hi] (hi may be kNoUpperEnd).
CLI::Option* AddNumber(CLI::App& app, const std::string& name, double& value, double lo, double hi,
                       const std::string& help);

// The rank this process has under mpirun (OpenMPI's OMPI_COMM_WORLD_RANK, or PMI's
// PMI_RANK / PMIX_RANK), read from the environment before MPI starts; 0 when not under a
// launcher. Errors of the command line are the same on every rank, so only rank 0 prints them.
int LauncherRank();

}  // namespace zephyr
