// `zephyr cycles`: the cycles of one operation on one virtual-PE layer, measured by running
// the operation through the engine on a machine of the chosen profile.
//
//   zephyr cycles --profile mpp --op add --bits 8          -> 25
//   zephyr cycles --op mul --bits 16 --bits2 12 --json
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <climits>
#include <functional>
#include <map>

#include "bitserial/float.h"
#include "bitserial/multi.h"
#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"

namespace zephyr {
namespace {

using namespace bitserial;

struct CyclesOptions {
  std::string profile = "wavetracer";
  std::string op = "add";
  int bits = 8;
  int bits2 = 0;
  int frac = 0;
  long long constant = 0x55;
  bool isUnsigned = false;
  bool external = false;
  std::string rounding = "floor";
  std::string overflow = "wrap";
  std::vector<std::string> overrides;
  bool json = false;
  std::string floatFormat;  // --float: the float ops' format (default from --bits)
};

bool IsFloatOp(const std::string& op) {
  const auto& names = FloatOpNames();
  return std::find(names.begin(), names.end(), op) != names.end();
}

// --float if given, else the IEEE interchange format of --bits (16, 32 or 64) with
// subnormals or flush-to-zero as the profile's machine did (floatSubnormals).
fixed::FloatFormat FloatFormatOf(const CyclesOptions& o, const MachineProfile& profile) {
  if (!o.floatFormat.empty()) return fixed::FloatFormat::Parse(o.floatFormat);
  const bool sub = profile.floatSubnormals;
  if (o.bits == 16) return {5, 10, sub};
  if (o.bits == 32) return {8, 23, sub};
  if (o.bits == 64) return {11, 52, sub};
  throw UserError(
      fmt::format("--op float operations take --bits 16, 32 or 64 (IEEE binary16/"
                  "32/64) or --float eXmY, got --bits {}",
                  o.bits));
}

// The f* operations: the float format from --float or --bits; the conversions (ftofixed,
// ffromfixed) take the fixed side from --bits/--frac/--unsigned and the float format from
// --float (default binary32 as the profile keeps it).
void RunFloatCycles(const CyclesOptions& o, const MachineProfile& profile,
                    const fixed::Format& fixedSide, const fixed::Policy& policy) {
  const bool conversion = o.op == "ftofixed" || o.op == "ffromfixed";
  const fixed::FloatFormat f = conversion && o.floatFormat.empty()
                                   ? fixed::FloatFormat{8, 23, profile.floatSubnormals}
                                   : FloatFormatOf(o, profile);
  const CycleReport rep = FloatOpReport(
      profile, o.op, f, o.external ? Space::kExternal : Space::kInternal, fixedSide, policy);
  const double cycles = rep.OpCycles(o.op);
  const double mops = profile.physicalPes * profile.clockHz / cycles / 1e6;
  if (o.json) {
    nlohmann::json j = rep.Json();
    j["op"] = o.op;
    j["format"] = f.Name();
    if (conversion) j["fixed"] = fixedSide.Name();
    j["cycles"] = cycles;
    j["mops"] = mops;
    fmt::print("{}\n", j.dump(2));
  } else {
    fmt::print(
        "{} {}{} on profile {} ({} memory): {} cycles per layer ({:.3g} us at {:g} Hz; "
        "{:.0f} MOPS on {} PEs)\n",
        o.op, f.Name(), conversion ? (o.op == "ftofixed" ? " -> " : " <- ") + fixedSide.Name() : "",
        profile.name, o.external ? "external" : "internal", cycles, cycles / profile.clockHz * 1e6,
        profile.clockHz, mops, profile.physicalPes);
    fmt::print("{}", rep.Table());
  }
}

void RunCycles(const CyclesOptions& o) {
  MachineProfile profile = Profile(o.profile);
  for (const std::string& s : o.overrides) profile.Override(s);
  auto format = [&](int bits, const char* flag) {
    if (bits < 1 || bits > fixed::kMaxWidth)
      throw UserError(fmt::format("{} must be in 1..{}, got {}", flag, fixed::kMaxWidth, bits));
    if (o.frac < 0 || o.frac > bits - (o.isUnsigned ? 0 : 1))
      throw UserError(fmt::format("--frac {} does not fit {} {}-bit operands", o.frac,
                                  o.isUnsigned ? "unsigned" : "signed", bits));
    return o.isUnsigned ? fixed::Format::Unsigned(bits - o.frac, o.frac)
                        : fixed::Format::Signed(bits - 1 - o.frac, o.frac);
  };
  fixed::Policy policy;
  if (o.rounding == "nearest")
    policy.rounding = fixed::Rounding::kNearest;
  else if (o.rounding != "floor")
    throw UserError("--rounding must be floor or nearest, got '" + o.rounding + "'");
  if (o.overflow == "saturate")
    policy.overflow = fixed::OverflowPolicy::kSaturate;
  else if (o.overflow != "wrap")
    throw UserError("--overflow must be wrap or saturate, got '" + o.overflow + "'");
  if (IsFloatOp(o.op)) {
    const bool conversion = o.op == "ftofixed" || o.op == "ffromfixed";
    return RunFloatCycles(o, profile, conversion ? format(o.bits, "--bits") : fixed::Format{},
                          policy);
  }
  const fixed::Format fa = format(o.bits, "--bits");
  const fixed::Format fb = format(o.bits2 ? o.bits2 : o.bits, "--bits2");

  Machine m(profile);
  std::optional<Space> space;
  if (o.external) space = Space::kExternal;
  Multi a(m, fa, "a", space), b(m, fb, "b", space);
  const fixed::Format out = fa;
  using Run = std::function<Multi()>;
  const std::map<std::string, std::pair<std::string, Run>> ops = {
      {"add", {"add", [&] { return Add(a, b, out, policy); }}},
      {"sub", {"sub", [&] { return Sub(a, b, out, policy); }}},
      {"neg", {"neg", [&] { return Neg(a, out, policy); }}},
      {"abs", {"abs", [&] { return Abs(a, out, policy); }}},
      {"mul", {"mul", [&] { return Mul(a, b, out, policy); }}},
      {"mul-uni",
       {"mulUni",
        [&] {
          fixed::Format fc = format(o.bits2 ? o.bits2 : o.bits, "--bits2");
          fixed::Fixed c = fixed::Fixed::FromBits(
              fc, fixed::BigInt(static_cast<unsigned long long>(o.constant)) &
                      ((fixed::BigInt(1) << fc.Width()) - 1));
          return Mul(a, Uni{c}, out, policy);
        }}},
      {"square", {"square", [&] { return Square(a, out, policy); }}},
      {"compare", {"compare", [&] { return a < b; }}},
      {"min", {"min", [&] { return Min(a, b, out, policy); }}},
      {"max", {"max", [&] { return Max(a, b, out, policy); }}},
      {"select",
       {"select",
        [&] {
          Multi mask = Multi(m, BoolFormat(), "mask");
          m.Report().Clear();
          return Select(mask, a, b, out, policy);
        }}},
      {"shift", {"shift", [&] { return Shift(a, 1, out, policy); }}},
      {"div", {"div", [&] { return Div(a, b, out, policy); }}},
      {"sqrt", {"sqrt", [&] { return Sqrt(a, out, policy); }}},
  };
  auto it = ops.find(o.op);
  if (it == ops.end()) {
    std::string known;
    for (auto& [name, v] : ops) known += (known.empty() ? "" : ", ") + name;
    for (const std::string& name : FloatOpNames()) known += ", " + name;
    throw UserError(fmt::format("--op '{}' is not an operation (known: {})", o.op, known));
  }
  m.Report().Clear();
  Multi r = it->second.second();
  const CycleReport& rep = m.Report();
  const double cycles = rep.OpCycles(it->second.first);
  if (o.json) {
    nlohmann::json j = rep.Json();
    j["op"] = o.op;
    j["operands"] = {fa.Name(), fb.Name()};
    j["result"] = out.Name();
    j["cycles"] = cycles;
    fmt::print("{}\n", j.dump(2));
  } else {
    fmt::print(
        "{} {} x {} -> {} on profile {} ({} memory): {} cycles per layer "
        "({:.3g} us at {:g} Hz)\n",
        o.op, fa.Name(), fb.Name(), out.Name(), profile.name, o.external ? "external" : "internal",
        cycles, cycles / profile.clockHz * 1e6, profile.clockHz);
    fmt::print("{}", rep.Table());
  }
}

CommandRegistration reg("cycles", [](CLI::App& program) {
  auto opts = std::make_shared<CyclesOptions>();
  CLI::App* cmd = program.add_subcommand(
      "cycles", "Print the machine cycles of one bit-serial operation on one virtual-PE layer");
  cmd->add_option("--machine,--profile", opts->profile,
                  "Machine profile: a built-in name (zephyr profile list) or a profile file");
  cmd->add_option(
      "--op", opts->op,
      "Operation: add sub neg abs mul mul-uni square div sqrt compare min max select shift; "
      "float: fadd fsub fmul fdiv fsqrt fmin fmax fcompare ftofixed ffromfixed");
  cmd->add_option(
      "--float", opts->floatFormat,
      "Float format of the f* operations, eXmY[ftz] (default: binary16/32/64 by --bits; "
      "binary32 for ftofixed/ffromfixed, whose fixed side is --bits/--frac)");
  AddInteger(*cmd, "--bits", opts->bits, 1, fixed::kMaxWidth,
             "Width of the first operand (and of the result)");
  AddInteger(*cmd, "--bits2", opts->bits2, 1, fixed::kMaxWidth,
             "Width of the second operand / the constant (default --bits)");
  AddInteger(*cmd, "--frac", opts->frac, 0, fixed::kMaxWidth, "Fraction bits of the operands");
  AddInteger(*cmd, "--constant", opts->constant, LLONG_MIN, LLONG_MAX,
             "The uni constant's bits for mul-uni");
  cmd->add_flag("--unsigned", opts->isUnsigned, "Unsigned operands (default signed)");
  cmd->add_flag("--external", opts->external, "Operands and result in external PE memory");
  cmd->add_option("--rounding", opts->rounding, "floor or nearest");
  cmd->add_option("--overflow", opts->overflow, "wrap or saturate");
  cmd->add_option("--set", opts->overrides, "Override a profile entry, e.g. --set readExternal=4");
  cmd->add_flag("--json", opts->json, "Print the cycle report as JSON");
  cmd->callback([opts] { RunCycles(*opts); });
});

}  // namespace
}  // namespace zephyr
