// fixed/named.h — an enumeration's names in one table: the name of a value (reports, JSON,
// messages) and the value of a name (the command line, a message from a worker), so that no
// room keeps a switch of strings of its own.
//
//   inline constexpr NamedValues<Precision, 2> kPrecisionNames{{{{Precision::kFloat, "float"},
//                                                               {Precision::kDouble, "double"}}}};
//   kPrecisionNames.NameOf(Precision::kFloat)   // "float"
//   kPrecisionNames.Find("double")              // Precision::kDouble; nullopt for no such name
//   kPrecisionNames.List()                      // "float or double"
//
// A table may give one value several names (an alias after its name); NameOf gives the first,
// List the first of each value. hosts/cmd/flags.h's AddNamed parses a flag by its table and
// names the flag in the message; a lower room that reads a name (a worker's message) uses
// Parse, which names what the value is.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "fixed/check.h"

namespace zephyr {

template <class E>
struct Named {
  E value;
  const char* name;
};

template <class E, size_t N>
struct NamedValues {
  std::array<Named<E>, N> entries;

  // The value's first name; "?" for a value the table lacks (a programming error upstream).
  constexpr const char* NameOf(E value) const {
    for (const Named<E>& e : entries)
      if (e.value == value) return e.name;
    return "?";
  }
  constexpr std::optional<E> Find(std::string_view name) const {
    for (const Named<E>& e : entries)
      if (name == e.name) return e.value;
    return std::nullopt;
  }
  // The names, one per value, as a message lists them: "a, b or c".
  std::string List() const {
    std::string out;
    size_t shown = 0, values = 0;
    for (size_t i = 0; i < N; ++i) values += IsFirstName(i);
    for (size_t i = 0; i < N; ++i) {
      if (!IsFirstName(i)) continue;
      out += shown == 0 ? "" : (shown + 1 == values ? " or " : ", ");
      out += entries[i].name;
      ++shown;
    }
    return out;
  }
  // The value named `name`; UserError "WHAT: expected a, b or c, got 'NAME'" otherwise.
  E Parse(std::string_view name, std::string_view what) const {
    if (const std::optional<E> v = Find(name)) return *v;
    throw UserError(std::string(what) + ": expected " + List() + ", got '" + std::string(name) +
                    "'");
  }

 private:
  constexpr bool IsFirstName(size_t i) const {
    for (size_t k = 0; k < i; ++k)
      if (entries[k].value == entries[i].value) return false;
    return true;
  }
};

}  // namespace zephyr
