#include "hosts/cmd/flags.h"

#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "fmt/format.h"

namespace zephyr {

namespace {

// What a message may show of a flag's text: printable ASCII, at most 40 bytes.
std::string Shown(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size() && i < 40; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    out += (c >= 0x20 && c < 0x7f) ? std::string(1, char(c)) : fmt::format("\\x{:02x}", c);
  }
  if (text.size() > 40) out += "...";
  return out;
}

[[noreturn]] void Refuse(const std::string& flag, const std::string& expected,
                         const std::string& text, const std::string& why = "") {
  throw CLI::ValidationError(flag, "expected " + expected + ", got '" + Shown(text) + "'" +
                                       (why.empty() ? "" : " (" + why + ")"));
}

std::string Range(double lo, double hi) {
  if (std::isinf(hi)) return fmt::format(">= {}", lo);
  return fmt::format("{}..{}", lo, hi);
}

template <class T>
T ParseWhole(const std::string& flag, const std::string& text, T lo, T hi, const std::string& why) {
  const std::string expected = fmt::format("an integer {}..{}", lo, hi);
  std::string_view s = text;
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  T value{};
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value, 10);
  if (ec == std::errc::result_out_of_range) Refuse(flag, expected, text, why);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty())
    Refuse(flag, expected, text, why);
  if (value < lo || value > hi) Refuse(flag, expected, text, why);
  return value;
}

}  // namespace

void RefuseFlag(const std::string& flag, const std::string& expected, const std::string& text) {
  Refuse(flag, expected, text);
}

int64_t ParseIntegerFlag(const std::string& flag, const std::string& text, int64_t lo, int64_t hi,
                         const std::string& why) {
  return ParseWhole<int64_t>(flag, text, lo, hi, why);
}

uint64_t ParseUnsignedFlag(const std::string& flag, const std::string& text, uint64_t lo,
                           uint64_t hi, const std::string& why) {
  if (!text.empty() && text[0] == '-')
    Refuse(flag, fmt::format("an integer {}..{}", lo, hi), text, why);
  return ParseWhole<uint64_t>(flag, text, lo, hi, why);
}

double ParseNumberFlag(const std::string& flag, const std::string& text, double lo, double hi) {
  const std::string expected = "a number " + Range(lo, hi);
  std::string_view s = text;
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  double value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty() || !std::isfinite(value))
    Refuse(flag, expected, text);
  if (!(value >= lo && value <= hi)) Refuse(flag, expected, text);
  return value;
}

CLI::Option* AddParsedOption(CLI::App& app, const std::string& name,
                             std::function<void(const std::string&)> set,
                             const std::string& typeName, const std::string& defaultText,
                             const std::string& help) {
  CLI::Option* o = app.add_option(
      name,
      [set = std::move(set)](const CLI::results_t& r) {
        set(r.back());
        return true;
      },
      help);
  o->type_name(typeName);
  o->default_str(defaultText);
  return o;
}

CLI::Option* AddNumber(CLI::App& app, const std::string& name, double& value, double lo, double hi,
                       const std::string& help) {
  return AddParsedOption(
      app, name,
      [&value, name, lo, hi](const std::string& text) {
        value = ParseNumberFlag(name, text, lo, hi);
      },
      "NUMBER " + Range(lo, hi), fmt::format("{}", value), help);
}

int LauncherRank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"})
    if (const char* v = std::getenv(name)) return std::atoi(v);
  return 0;
}

}  // namespace zephyr
