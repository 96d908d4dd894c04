#include "flowire/common/config.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "flowire/common/error.hpp"
#include "flowire_test.hpp"

using namespace flowire::config;
using flowire::units::Dimension;

namespace {

Schema test_schema() {
  Schema s;
  s.add({"flow", Type::Section, "", Dimension::None, "flow section", {}, {}});
  s.add({"flow.solver",
         Type::Enum,
         "superposition",
         Dimension::None,
         "solver",
         {"superposition", "sparse", "dense_inverse"},
         {}});
  s.add({"flow.viscosity", Type::Number, "3.5e-3", Dimension::Viscosity, "viscosity", {}, {}});
  s.add({"flow.inlet", Type::Section, "{}", Dimension::None, "inlet", {}, {}});
  s.add({"flow.inlet.pressure", Type::NumberOrSection, "13000", Dimension::Pressure, "inlet pressure", {}, {}});
  s.add({"flow.inlet.pressure.systolic", Type::Number, "", Dimension::Pressure, "", {}, {}});
  s.add({"wire", Type::Section, "", Dimension::None, "wire", {}, {}});
  s.add({"wire.radius", Type::Number, "0.45 mm", Dimension::Length, "radius", {}, {}});
  s.add({"wire.segments", Type::Integer, "100", Dimension::None, "segments", {}, {}});
  s.add({"wire.base", Type::Section, "", Dimension::None, "", {}, {}});
  s.add({"wire.base.direction", Type::Vector3, "", Dimension::None, "", {}, {}});
  s.add({"loads", Type::List, "", Dimension::None, "", {}, {}});
  s.add({"loads[].type", Type::Enum, "", Dimension::None, "", {"tip_force", "gravity"}, {}});
  s.add({"loads[].value", Type::Vector3, "", Dimension::Force, "", {}, {}});
  s.add({"loads[].scale", Type::Number, "1", Dimension::None, "", {}, {}});
  return s;
}

std::string error_of(const std::string& text, const std::vector<std::string>& sets = {}) {
  try {
    load_config_text(text, "scene.yaml", test_schema(), sets);
  } catch (const flowire::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Config, AbsentSectionsStayAbsentAndPresentOnesGetDefaults) {
  const auto c = load_config_text("flow:\n  solver: sparse\n", "scene.yaml", test_schema());
  EXPECT_TRUE(c.has_section("flow"));
  EXPECT_FALSE(c.has_section("wire"));
  EXPECT_EQ(c.string("flow.solver"), "sparse");
  EXPECT_DOUBLE_EQ(c.number("flow.viscosity"), 3.5e-3);
  EXPECT_DOUBLE_EQ(c.number("flow.inlet.pressure"), 13000.0);  // nested default section
  EXPECT_EQ(c.where("flow.viscosity"), "default: flow.viscosity");
  EXPECT_EQ(c.where("flow.solver"), "scene.yaml:2: flow.solver");
}

TEST(Config, UnitsAreConverted) {
  const auto c = load_config_text("wire:\n  radius: 0.2 mm\nflow:\n  viscosity: 4 cP\n", "s", test_schema());
  EXPECT_DOUBLE_EQ(c.number("wire.radius"), 0.2e-3);
  EXPECT_DOUBLE_EQ(c.number("flow.viscosity"), 4e-3);
}

TEST(Config, UnknownKeyNamesLineAndSuggests) {
  const auto msg = error_of("flow:\n  solvr: sparse\n");
  EXPECT_NE(msg.find("scene.yaml:2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("flow.solvr"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean 'solver'"), std::string::npos) << msg;
  EXPECT_NE(error_of("flwo: {}\n").find("scene.yaml:1"), std::string::npos);
}

TEST(Config, BadValuesNameTheKey) {
  EXPECT_NE(error_of("flow:\n  solver: magic\n").find("not one of"), std::string::npos);
  EXPECT_NE(error_of("wire:\n  radius: 2 mmHg\n").find("scene.yaml:2: wire.radius"), std::string::npos);
  EXPECT_NE(error_of("wire:\n  segments: 2.5\n").find("whole number"), std::string::npos);
  EXPECT_NE(error_of("wire:\n  base: {direction: [1, 0]}\n").find("expected 3 numbers"), std::string::npos);
  EXPECT_NE(error_of("flow: [1, 2]\n").find("must be a map"), std::string::npos);
  EXPECT_NE(error_of("flow:\n  solver: [\n").find("YAML syntax error"), std::string::npos);
}

TEST(Config, NumberOrSectionAcceptsBoth) {
  const auto a = load_config_text("flow:\n  inlet: {pressure: 100 mmHg}\n", "s", test_schema());
  EXPECT_NEAR(a.number("flow.inlet.pressure"), 13332.2387415, 1e-6);
  const auto b = load_config_text("flow:\n  inlet: {pressure: {systolic: 120 mmHg}}\n", "s", test_schema());
  EXPECT_NEAR(b.number("flow.inlet.pressure.systolic"), 120 * 133.322387415, 1e-9);
}

TEST(Config, ListsValidateEachItemAndFillDefaults) {
  const auto c = load_config_text("loads:\n  - {type: tip_force, value: [0, -1 mN, 0]}\n  - {type: gravity}\n", "s",
                                  test_schema());
  ASSERT_EQ(c.count("loads"), 2);
  EXPECT_EQ(c.string("loads[1].type"), "gravity");
  EXPECT_DOUBLE_EQ(c.vector3("loads[0].value").y(), -1e-3);
  EXPECT_DOUBLE_EQ(c.number("loads[1].scale"), 1.0);
  EXPECT_NE(error_of("loads:\n  - {type: tip_force, valu: [0,0,0]}\n").find("scene.yaml:2"), std::string::npos);
}

TEST(Config, SetOverridesAndRejectsUnknownKeys) {
  const auto c = load_config_text("flow: {}\n", "s", test_schema(),
                                  {"flow.solver=dense_inverse", "wire.base.direction=[0,0,1]", "wire.radius=1 mm"});
  EXPECT_EQ(c.string("flow.solver"), "dense_inverse");
  EXPECT_EQ(c.vector3("wire.base.direction"), Eigen::Vector3d(0, 0, 1));
  EXPECT_DOUBLE_EQ(c.number("wire.radius"), 1e-3);
  EXPECT_EQ(c.where("flow.solver"), "--set: flow.solver");
  EXPECT_NE(error_of("flow: {}\n", {"flow.nothing=3"}).find("unknown key 'flow.nothing'"), std::string::npos);
  EXPECT_NE(error_of("flow: {}\n", {"novalue"}).find("KEY=VALUE"), std::string::npos);
}

TEST(Config, AMisspeltKeyOfASectionWithNamedEntriesSaysSoAndWhere) {
  // wall.<branch> takes a branch's own values as a map: a scalar under an unknown name is a
  // misspelt key of wall (named as such, with the keys allowed) at its line, or at --set.
  Schema s;
  s.add({"wall", Type::Section, "", Dimension::None, "", {}, {}});
  s.add({"wall.thickness", Type::Number, "", Dimension::Length, "", {}, {}});
  s.add({"wall.youngs_modulus", Type::Number, "1 MPa", Dimension::Pressure, "", {}, {}});
  s.add({"wall.*", Type::Section, "", Dimension::None, "", {}, {}});
  s.add({"wall.*.youngs_modulus", Type::Number, "", Dimension::Pressure, "", {}, {}});
  auto error = [&](const std::string& text, const std::vector<std::string>& sets) {
    try {
      load_config_text(text, "scene.yaml", s, sets);
    } catch (const flowire::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string in_file = error("wall:\n  thicknes: 1 mm\n", {});
  EXPECT_NE(in_file.find("scene.yaml:2"), std::string::npos) << in_file;
  EXPECT_NE(in_file.find("'wall.thicknes' is not a key of wall (allowed: thickness, youngs_modulus)"),
            std::string::npos)
      << in_file;
  const std::string set = error("wall: {}\n", {"wall.bogus=1"});
  EXPECT_EQ(set.rfind("--set:", 0), 0u) << set;
  EXPECT_NE(set.find("'wall.bogus' is not a key of wall"), std::string::npos) << set;
  // A named entry given as a map is a branch's values.
  const auto c = load_config_text("wall:\n  iliac:\n    youngs_modulus: 2 MPa\n", "scene.yaml", s, {});
  EXPECT_DOUBLE_EQ(c.number("wall.iliac.youngs_modulus"), 2e6);
}

TEST(Config, SchemaMarkdownListsEveryKey) {
  const auto md = test_schema().markdown();
  EXPECT_NE(md.find("`flow.solver`"), std::string::npos);
  EXPECT_NE(md.find("superposition \\| sparse \\| dense_inverse"), std::string::npos);
  EXPECT_NE(md.find("| Pa*s |"), std::string::npos);
}

TEST(Config, DeclaredDefaultsAreThoseOfTheSectionGivenEmpty) {
  const auto d = declared_defaults(test_schema(), "wire");
  EXPECT_DOUBLE_EQ(d.number("wire.radius"), 0.45e-3);
  EXPECT_EQ(d.integer("wire.segments"), 100);
  EXPECT_EQ(d.where("wire.radius"), "default: wire.radius");
  EXPECT_FALSE(d.has_section("wire.base"));  // no default: absent, as in a scene
  EXPECT_FALSE(d.has_section("flow"));
  // The same values as a scene that writes the section empty.
  const auto c = load_config_text("wire: {}\n", "scene.yaml", test_schema());
  EXPECT_EQ(d.values().size(), c.values().size());
  for (const auto& [path, v] : c.values()) {
    ASSERT_TRUE(d.has(path)) << path;
    EXPECT_EQ(d.values().at(path).number, v.number) << path;
  }
  EXPECT_THROW((void)declared_defaults(test_schema(), "wire.radius"), flowire::Error);  // a key, not a section
  EXPECT_THROW((void)declared_defaults(test_schema(), "catheter"), flowire::Error);     // not declared
}

TEST(Config, KeysDeclaredByFieldsEqualKeysDeclaredWhole) {
  Schema s;
  s.add("wire", Type::Section, "", Dimension::None, "wire");
  s.add("wire.tip", Type::Enum, "j", Dimension::None, "tip shape", {"straight", "j"});
  const Key* k = s.find("wire.tip");
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->default_text, "j");
  EXPECT_EQ(k->doc, "tip shape");
  EXPECT_EQ(k->choices, (std::vector<std::string>{"straight", "j"}));
  EXPECT_THROW(s.add("wire.tip", Type::Number, "", Dimension::None, "again"), flowire::Error);
}

namespace {

/// A schema with one key of each kind of range.
Schema ranged_schema() {
  Schema s;
  s.add("wire", Type::Section, "", Dimension::None, "wire");
  s.add("wire.length", Type::Number, "1", Dimension::Length, "length").positive();
  s.add("wire.damping", Type::Number, "0", Dimension::None, "damping").non_negative();
  s.add("wire.share", Type::Number, "", Dimension::None, "a fraction").fraction();
  s.add("wire.ratio", Type::Number, "", Dimension::None, "ratio").above(-1.0).below(0.5);
  s.add("wire.segments", Type::Integer, "10", Dimension::None, "segments").at_least(1).at_most(1000);
  s.add("wire.base", Type::Vector3, "", Dimension::Length, "base position");
  s.add("loads", Type::List, "", Dimension::None, "loads");
  s.add("loads[].s", Type::Number, "", Dimension::Length, "arc length").non_negative();
  return s;
}

std::string ranged_error(const std::string& text, const std::vector<std::string>& sets = {}) {
  try {
    (void)load_config_text(text, "scene.yaml", ranged_schema(), sets);
  } catch (const flowire::Error& e) {
    EXPECT_EQ(e.kind(), flowire::ErrorKind::Input) << e.what();
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ConfigRange, ChainedDeclarationsSetTheBoundsOfTheKeyJustAdded) {
  const Schema s = ranged_schema();
  const Range& length = s.find("wire.length")->range;
  EXPECT_EQ(length.lower, 0.0);
  EXPECT_TRUE(length.lower_open);
  EXPECT_FALSE(std::isfinite(length.upper));
  const Range& segments = s.find("wire.segments")->range;
  EXPECT_EQ(segments.lower, 1.0);
  EXPECT_EQ(segments.upper, 1000.0);
  EXPECT_FALSE(segments.lower_open || segments.upper_open);
  EXPECT_FALSE(s.find("wire.base")->range.bounded());  // finite is the default, no bound
  EXPECT_TRUE(s.find("wire.share")->range.bounded());
  // How the reference page writes them.
  EXPECT_EQ(length.text(), "> 0");
  EXPECT_EQ(s.find("wire.damping")->range.text(), ">= 0");
  EXPECT_EQ(s.find("wire.share")->range.text(), "[0, 1]");
  EXPECT_EQ(s.find("wire.ratio")->range.text(), "(-1, 0.5)");
  EXPECT_EQ(segments.text(), "[1, 1000]");
  EXPECT_EQ(s.find("wire.base")->range.text(), "");
  Schema upper;
  upper.add("depth", Type::Integer, "", Dimension::None, "").at_most(24);
  EXPECT_EQ(upper.find("depth")->range.text(), "<= 24");
  EXPECT_FALSE(upper.find("depth")->range.contains(25));
  EXPECT_TRUE(upper.find("depth")->range.contains(-3));
}

TEST(ConfigRange, ContainsHonoursOpenAndClosedBoundsAndRefusesNonFiniteValues) {
  const Schema s = ranged_schema();
  const Range& ratio = s.find("wire.ratio")->range;
  EXPECT_FALSE(ratio.contains(-1.0));
  EXPECT_TRUE(ratio.contains(std::nextafter(-1.0, 0.0)));
  EXPECT_TRUE(ratio.contains(std::nextafter(0.5, 0.0)));
  EXPECT_FALSE(ratio.contains(0.5));
  const Range& share = s.find("wire.share")->range;
  EXPECT_TRUE(share.contains(0.0));
  EXPECT_TRUE(share.contains(1.0));
  EXPECT_FALSE(share.contains(std::nextafter(1.0, 2.0)));
  EXPECT_FALSE(share.contains(-std::numeric_limits<double>::denorm_min()));
  const Range any;
  EXPECT_TRUE(any.contains(-1e300));
  EXPECT_FALSE(any.contains(std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(any.contains(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(share.contains(std::numeric_limits<double>::quiet_NaN()));
}

TEST(ConfigRange, ARangeOnAKeyThatIsNoNumberOrThatHoldsNoValueIsAUsageError) {
  Schema s;
  EXPECT_THROW(s.positive(), flowire::Error);  // no key yet
  s.add("wire", Type::Section, "", Dimension::None, "wire");
  EXPECT_THROW(s.positive(), flowire::Error);
  s.add("wire.shape", Type::Enum, "j", Dimension::None, "shape", {"j"});
  EXPECT_THROW(s.non_negative(), flowire::Error);
  s.add("wire.length", Type::Number, "", Dimension::Length, "length");
  EXPECT_THROW(s.at_least(2.0).at_most(1.0), flowire::Error);
  Schema t;
  t.add("x", Type::Number, "", Dimension::None, "");
  EXPECT_THROW(t.above(1.0).at_most(1.0), flowire::Error);  // (1, 1] is empty
  Schema u;
  u.add("x", Type::Number, "", Dimension::None, "");
  EXPECT_NO_THROW(u.at_least(1.0).at_most(1.0));  // [1, 1] holds 1
  try {
    Schema v;
    v.add("wire", Type::Section, "", Dimension::None, "wire");
    v.positive();
  } catch (const flowire::Error& e) {
    EXPECT_EQ(e.kind(), flowire::ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("'wire'"), std::string::npos) << e.what();
  }
}

TEST(ConfigRange, AValueOutsideItsRangeNamesFileLineKeyValueUnitAndLimit) {
  const std::string e = ranged_error("wire:\n  damping: 0.5\n  length: -0.5 mm\n");
  EXPECT_EQ(e.rfind("scene.yaml:3: wire.length = -0.0005 m: ", 0), 0u) << e;
  EXPECT_NE(e.find("must be positive (> 0)"), std::string::npos) << e;
  EXPECT_NE(
      ranged_error("wire:\n  damping: -0.1\n").find("scene.yaml:2: wire.damping = -0.1: must not be negative (>= 0)"),
      std::string::npos);
  EXPECT_NE(ranged_error("wire:\n  share: 1.5\n").find("wire.share = 1.5: must be in [0, 1]"), std::string::npos);
  EXPECT_NE(ranged_error("wire:\n  ratio: 0.5\n").find("wire.ratio = 0.5: must be in (-1, 0.5)"), std::string::npos);
  EXPECT_NE(ranged_error("wire:\n  segments: 0\n").find("wire.segments = 0: must be in [1, 1000]"), std::string::npos);
  EXPECT_NE(ranged_error("wire:\n  segments: 1001\n").find("[1, 1000]"), std::string::npos);
  // At a closed limit and just inside an open one: accepted.
  EXPECT_EQ(ranged_error("wire:\n  damping: 0\n  share: 1\n  segments: 1000\n  ratio: -0.999999\n  length: 1e-300\n"),
            "");
}

TEST(ConfigRange, OverridesListItemsAndDefaultsAreCheckedToo) {
  // --set names itself as the place.
  EXPECT_NE(ranged_error("wire: {}\n", {"wire.length=0"}).find("--set: wire.length = 0 m: must be positive (> 0)"),
            std::string::npos);
  EXPECT_EQ(ranged_error("wire: {length: -1}\n", {"wire.length=2 cm"}), "");  // the override replaces the bad value
  // A list item by its index and line.
  const std::string e = ranged_error("loads:\n  - s: 1 cm\n  - s: -2 cm\n");
  EXPECT_EQ(e.rfind("scene.yaml:3: loads[1].s = -0.02 m: ", 0), 0u) << e;
  // A default outside its own range is a declaration error, named as the default.
  Schema bad;
  bad.add("wire", Type::Section, "", Dimension::None, "wire");
  bad.add("wire.length", Type::Number, "-1", Dimension::Length, "length").positive();
  try {
    (void)load_config_text("wire: {}\n", "scene.yaml", bad);
    ADD_FAILURE() << "a default outside its range was filled in";
  } catch (const flowire::Error& err) {
    EXPECT_NE(std::string(err.what()).find("default: wire.length = -1 m"), std::string::npos) << err.what();
  }
}

TEST(ConfigRange, EveryNumberMustBeFiniteAfterItsUnitIsApplied) {
  // 1e308 min is a finite number as written and infinite in s, the SI unit it is converted to.
  Schema s;
  s.add("solve", Type::Section, "", Dimension::None, "");
  s.add("solve.duration", Type::Number, "", Dimension::Time, "");
  s.add("solve.position", Type::Vector3, "", Dimension::Time, "");
  s.add("solve.list", Type::NumberList, "", Dimension::Time, "");
  s.add("solve.count", Type::NumberOrSection, "", Dimension::Time, "");
  for (const std::string text : {"solve: {duration: 1e308 min}\n", "solve: {position: [0, 1e308 min, 0]}\n",
                                 "solve: {list: [1, 2, 1e308 min]}\n", "solve: {count: 1e308 min}\n"}) {
    try {
      (void)load_config_text(text, "scene.yaml", s);
      ADD_FAILURE() << text << ": an infinite value was accepted";
    } catch (const flowire::Error& e) {
      EXPECT_EQ(e.kind(), flowire::ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("must be a finite number"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("scene.yaml:1: solve."), std::string::npos) << e.what();
    }
  }
  // The component of a vector out of range is named by its index.
  Schema d;
  d.add("dir", Type::Vector3, "", Dimension::None, "").at_least(-1.0).at_most(1.0);
  try {
    (void)load_config_text("dir: [0, 2, 0]\n", "scene.yaml", d);
    ADD_FAILURE() << "a component outside [-1, 1] was accepted";
  } catch (const flowire::Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene.yaml:1: dir[1] = 2: must be in [-1, 1]"), std::string::npos)
        << e.what();
  }
}

TEST(ConfigRange, TheReferencePageShowsTheRangeColumn) {
  const std::string md = ranged_schema().markdown();
  EXPECT_NE(md.find("| key | type | default | unit | range | description |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `wire.length` | number | `1` | m | `> 0` | length |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `wire.base` | [x, y, z] |  | m |  | base position |"), std::string::npos) << md;
}

TEST(ConfigRange, CheckRangeIsTheLoadersCheck) {
  const Key* k = ranged_schema().find("wire.length");
  ASSERT_NE(k, nullptr);
  EXPECT_NO_THROW(check_range(*k, 0.1, "--param", "wire.length"));
  try {
    check_range(*k, -2.0, "--param", "wire.length");
    ADD_FAILURE() << "a negative length passed";
  } catch (const flowire::Error& e) {
    EXPECT_EQ(std::string(e.what()), "--param: wire.length = -2 m: " + k->range.requirement());
  }
}
