// fixed/named.h: an enumeration's names in one table, both ways.
#include "fixed/named.h"

#include <gtest/gtest.h>

#include <string>

namespace zephyr {
namespace {

enum class Colour { kRed, kGreen, kBlue };
constexpr NamedValues<Colour, 4> kColours{{{{Colour::kRed, "red"},
                                            {Colour::kGreen, "green"},
                                            {Colour::kBlue, "blue"},
                                            {Colour::kRed, "rouge"}}}};

TEST(NamedValues, EveryNameGivesItsValueAndEveryValueItsFirstName) {
  for (const Named<Colour>& e : kColours.entries) {
    EXPECT_EQ(kColours.Find(e.name), e.value) << e.name;
    EXPECT_EQ(kColours.Parse(e.name, "colour"), e.value) << e.name;
    EXPECT_EQ(kColours.Find(kColours.NameOf(e.value)), e.value) << e.name;
  }
  EXPECT_STREQ(kColours.NameOf(Colour::kRed), "red");  // the alias is never the name
  static_assert(kColours.Find("green") == Colour::kGreen);
}

TEST(NamedValues, AnUnknownNameIsRefusedWithTheListAndWhatItWasFor) {
  EXPECT_EQ(kColours.List(), "red, green or blue");  // one name per value, no alias
  EXPECT_FALSE(kColours.Find("Red").has_value());    // exact: no case folding
  EXPECT_FALSE(kColours.Find("").has_value());
  try {
    kColours.Parse("mauve", "the set-up's colour");
    FAIL() << "mauve parsed";
  } catch (const UserError& e) {
    EXPECT_STREQ(e.what(), "the set-up's colour: expected red, green or blue, got 'mauve'");
  }
}

}  // namespace
}  // namespace zephyr
