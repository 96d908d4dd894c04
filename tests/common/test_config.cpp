#include "flowire/common/config.hpp"

#include <gtest/gtest.h>

#include "flowire/common/error.hpp"
#include "flowire_test.hpp"

using namespace flowire::config;
using flowire::units::Dimension;

namespace {

Schema test_schema() {
  Schema s;
  s.add({"flow", Type::Section, "", Dimension::None, "flow section", {}});
  s.add({"flow.solver",
         Type::Enum,
         "superposition",
         Dimension::None,
         "solver",
         {"superposition", "sparse", "dense_inverse"}});
  s.add({"flow.viscosity", Type::Number, "3.5e-3", Dimension::Viscosity, "viscosity", {}});
  s.add({"flow.inlet", Type::Section, "{}", Dimension::None, "inlet", {}});
  s.add({"flow.inlet.pressure", Type::NumberOrSection, "13000", Dimension::Pressure, "inlet pressure", {}});
  s.add({"flow.inlet.pressure.systolic", Type::Number, "", Dimension::Pressure, "", {}});
  s.add({"wire", Type::Section, "", Dimension::None, "wire", {}});
  s.add({"wire.radius", Type::Number, "0.45 mm", Dimension::Length, "radius", {}});
  s.add({"wire.segments", Type::Integer, "100", Dimension::None, "segments", {}});
  s.add({"wire.base", Type::Section, "", Dimension::None, "", {}});
  s.add({"wire.base.direction", Type::Vector3, "", Dimension::None, "", {}});
  s.add({"loads", Type::List, "", Dimension::None, "", {}});
  s.add({"loads[].type", Type::Enum, "", Dimension::None, "", {"tip_force", "gravity"}});
  s.add({"loads[].value", Type::Vector3, "", Dimension::Force, "", {}});
  s.add({"loads[].scale", Type::Number, "1", Dimension::None, "", {}});
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
