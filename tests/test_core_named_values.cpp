#include <gtest/gtest.h>

#include <string>

#include "core/named_values.hpp"
#include "edit/brush.hpp"
#include "haptics/force_model.hpp"
#include "io/export.hpp"
#include "io/planet_file.hpp"
#include "sand/settler.hpp"
#include "terrain/error_bounds.hpp"
#include "tracking/detector.hpp"

namespace ps {
namespace {

enum class Colour { kRed, kGreen, kBlue };
constexpr core::NameTable<Colour, 4> kColours{"colour",
                                              {{{Colour::kRed, "red"},
                                                {Colour::kGreen, "green"},
                                                {Colour::kBlue, "blue"},
                                                {Colour::kRed, "r"}}}};

std::string refusal(const std::string& text) {
  try {
    kColours.parse(text);
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(NamedValues, EveryNamePrintsAndParsesBackToItsValue) {
  for (const auto& e : kColours.entries) {
    EXPECT_EQ(kColours.parse(e.name), e.value) << e.name;
    EXPECT_EQ(kColours.parse(kColours.nameOf(e.value)), e.value) << e.name;
  }
}

TEST(NamedValues, AnAliasParsesButTheFirstNameIsPrinted) {
  EXPECT_EQ(kColours.parse("r"), Colour::kRed);
  EXPECT_STREQ(kColours.nameOf(Colour::kRed), "red");
  EXPECT_EQ(kColours.choices(), "red, green, blue");
}

TEST(NamedValues, ARefusalNamesTheSettingTheTextAndTheChoices) {
  EXPECT_EQ(refusal("Red"), "colour 'Red' is not one of red, green, blue");
  EXPECT_EQ(refusal(""), "colour '' is not one of red, green, blue");
  EXPECT_TRUE(kColours.contains(Colour::kBlue));
  EXPECT_FALSE(kColours.contains(Colour(7)));
  EXPECT_STREQ(kColours.nameOf(Colour(7)), "?");
}

// The project's own tables: each value's printed name parses back to it, and the aliases a
// user types (file extensions, long names) still work.
TEST(NamedValues, TheProjectsSettingsRoundTripThroughTheirNames) {
  for (auto m : {edit::BrushMode::kRaise, edit::BrushMode::kLower, edit::BrushMode::kSet})
    EXPECT_EQ(edit::brushModeFromString(edit::toString(m)), m);
  for (auto m : {sand::SettleMethod::kThermal, sand::SettleMethod::kDiffusionExplicit,
                 sand::SettleMethod::kDiffusionSemiImplicit})
    EXPECT_EQ(sand::settleMethodFromString(sand::toString(m)), m);
  for (auto f : {haptics::Fault::kNone, haptics::Fault::kDeviceLost, haptics::Fault::kNonFinite,
                 haptics::Fault::kJump, haptics::Fault::kTimeOrder, haptics::Fault::kNoTerrain})
    EXPECT_EQ(haptics::faultFromString(haptics::toString(f)), f);
  for (auto r : {tracking::ArucoRefinement::kNone, tracking::ArucoRefinement::kSubpix,
                 tracking::ArucoRefinement::kContour, tracking::ArucoRefinement::kAprilTag})
    EXPECT_EQ(tracking::arucoRefinementFromString(tracking::toString(r)), r);
  for (auto f : {io::ExportFormat::kPng16, io::ExportFormat::kTiff32, io::ExportFormat::kRaw32,
                 io::ExportFormat::kObj, io::ExportFormat::kPly, io::ExportFormat::kGlb})
    EXPECT_EQ(io::exportFormatFromName(io::toString(f)), f);

  EXPECT_EQ(io::exportFormatFromName("TIF"), io::ExportFormat::kTiff32);
  EXPECT_EQ(io::exportFormatFromName("f32"), io::ExportFormat::kRaw32);
  EXPECT_EQ(io::heightEncodingFromString("uint16"), io::HeightEncoding::kUint16);
  EXPECT_EQ(terrain::errorRuleFromString("hybrid"), terrain::ErrorRule::kHybridExact);
  EXPECT_EQ(terrain::toString(terrain::ErrorRule::kHybridExact), "hybrid-exact");
}

}  // namespace
}  // namespace ps
