// The declaration of every scene key (coupling/src/scene_schema.cpp): well formed (every
// key under a declared section, every enum default among its choices), every default a
// valid value of its unit, given in SI as written by hand here, and every example scene of
// examples/ accepted; a section a scene leaves out reads as its declared defaults.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire_test.hpp"
#include "scene_sections.hpp"

using namespace flowire;
using config::Type;
namespace fs = std::filesystem;

namespace {

std::string parent_of(const std::string& path) {
  const auto dot = path.rfind('.');
  return dot == std::string::npos ? std::string() : path.substr(0, dot);
}

TEST(SceneSchema, EveryKeyLiesUnderADeclaredSectionAndEveryEnumDefaultIsAChoice) {
  const auto& schema = coupling::scene_schema();
  ASSERT_GT(schema.keys().size(), 100u);
  std::set<std::string> seen;
  for (const auto& k : schema.keys()) {
    EXPECT_TRUE(seen.insert(k.path).second) << k.path << " declared twice";
    EXPECT_FALSE(k.doc.empty()) << k.path << " has no description";
    const std::string parent = parent_of(k.path);
    if (!parent.empty()) {
      const bool list_item = parent.size() > 2 && parent.compare(parent.size() - 2, 2, "[]") == 0;
      const config::Key* p = schema.find(list_item ? parent.substr(0, parent.size() - 2) : parent);
      ASSERT_NE(p, nullptr) << k.path << ": parent not declared";
      if (list_item) {
        EXPECT_EQ(p->type, Type::List) << k.path;
      } else {
        EXPECT_TRUE(p->type == Type::Section || p->type == Type::NumberOrSection) << k.path;
      }
      // A parent is declared before its children (the reference page reads top-down).
      EXPECT_LT(p - schema.keys().data(), &k - schema.keys().data()) << k.path;
    }
    if (k.type == Type::Enum) {
      EXPECT_FALSE(k.choices.empty()) << k.path;
      if (!k.default_text.empty()) {
        EXPECT_NE(std::find(k.choices.begin(), k.choices.end(), k.default_text), k.choices.end())
            << k.path << ": default '" << k.default_text << "' is not a choice";
      }
    } else {
      EXPECT_TRUE(k.choices.empty()) << k.path;
    }
  }
}

/// A scene with every declared section present and empty, so that every default is filled.
std::string every_section() {
  std::map<std::string, std::vector<std::string>> children;  // section -> child sections
  std::vector<std::string> top;
  for (const auto& k : coupling::scene_schema().keys()) {
    if (k.type != Type::Section || k.path.find("[]") != std::string::npos || k.path.find('*') != std::string::npos)
      continue;
    const std::string parent = parent_of(k.path);
    (parent.empty() ? top : children[parent]).push_back(k.path);
  }
  std::string yaml;
  auto emit = [&](auto&& self, const std::string& path, int depth) -> void {
    const std::string name = path.substr(path.rfind('.') == std::string::npos ? 0 : path.rfind('.') + 1);
    const auto it = children.find(path);
    yaml += std::string(static_cast<size_t>(2 * depth), ' ') + name + (it == children.end() ? ": {}\n" : ":\n");
    if (it != children.end())
      for (const auto& c : it->second) self(self, c, depth + 1);
  };
  for (const auto& t : top) emit(emit, t, 0);
  return yaml;
}

TEST(SceneSchema, EveryDefaultIsAValidValueAndReadsAsWrittenInSI) {
  const std::string yaml = every_section();
  const auto c = config::load_config_text(yaml, "every_section.yaml", coupling::scene_schema());
  // Every scalar key with a default now has a value (its text parsed with its unit), except
  // under a number-or-section without a default (flow.inlet.flow), which stays absent.
  const auto& schema = coupling::scene_schema();
  auto under_absent_choice = [&](const std::string& path) {
    for (std::string p = parent_of(path); !p.empty(); p = parent_of(p)) {
      const config::Key* key = schema.find(p);
      if (key && key->type == Type::NumberOrSection && key->default_text.empty()) return true;
    }
    return false;
  };
  for (const auto& k : schema.keys()) {
    if (k.default_text.empty() || k.path.find("[]") != std::string::npos || k.path.find('*') != std::string::npos ||
        under_absent_choice(k.path))
      continue;
    if (k.type == Type::Section || k.type == Type::List || k.type == Type::NumberOrSection) continue;
    EXPECT_TRUE(c.has(k.path)) << k.path << " (default '" << k.default_text << "') not filled\n" << yaml;
  }
  // The defaults in SI, worked out by hand from the values the keys document.
  const double mmHg = 13595.1 * 9.80665 * 1e-3;  // the conventional millimetre of mercury (ρ_Hg g h)
  const std::pair<const char*, double> si[] = {
      {"vessels.max_segment_length", 5e-3},
      {"vessels.generator.radius", 2e-3},
      {"vessels.generator.parent_radius", 5e-3},
      {"vessels.generator.angle", 0.6},
      {"vessels.generator.radius_ratio", std::pow(2.0, -1.0 / 3.0)},  // Murray's law for two equal daughters
      {"flow.viscosity", 3.5e-3},
      {"flow.density", 1060.0},
      {"flow.wall.youngs_modulus", 0.4e6},
      {"flow.inlet.pressure.systolic", 120.0 * mmHg},
      {"flow.inlet.pressure.diastolic", 80.0 * mmHg},
      {"flow.inlet.pressure.period", 0.8},
      {"wire.radius", 0.45e-3},
      {"wire.youngs_modulus", 60e9},
      {"wire.tip.length", 0.03},
      {"wire.tip.youngs_modulus", 10e9},
      {"wire.tip.bend_radius", 3e-3},
      {"wire.adapt.split_angle", 0.1},
      {"catheter.outer_radius", 1e-3},
      {"catheter.inner_radius", 0.55e-3},
      {"catheter.youngs_modulus", 2e9},
      {"catheter.initial_length", 0.02},
      {"insertion.initial_length", 0.02},
      {"coupling.steering.force", 5e-3},
      {"coupling.steering.range", 0.02},
      {"coupling.steering.offset", 0.01},
      {"solve.dt", 1e-3},
  };
  for (const auto& [path, value] : si) EXPECT_NEAR(c.number(path), value, 1e-12 * std::abs(value)) << path;
  EXPECT_EQ(c.integer("wire.segments"), 100);
  EXPECT_EQ(c.string("flow.model"), "poiseuille");
  EXPECT_EQ(c.string("coupling.drag"), "cylinder");
  EXPECT_EQ(c.string("coupling.occlusion"), "annulus");
  EXPECT_TRUE(c.boolean("contact.enabled"));
  EXPECT_EQ(c.vector3("wire.base.direction"), Eigen::Vector3d(1, 0, 0));
}

TEST(SceneSchema, EveryExampleSceneIsAccepted) {
  const fs::path examples = fs::path(FLOWIRE_SOURCE_DIR) / "examples";
  int scenes = 0;
  for (const auto& e : fs::recursive_directory_iterator(examples)) {
    // examples/studies holds study files (flowire study), checked by Study.ExampleStudiesAreValid.
    if (e.path().extension() != ".yaml" || e.path().parent_path().filename() == "studies") continue;
    ++scenes;
    try {
      const auto c = config::load_config(e.path().string(), coupling::scene_schema());
      EXPECT_TRUE(c.has_section("vessels") || c.has_section("wire") || c.has_section("fem")) << e.path();
    } catch (const std::exception& ex) {
      ADD_FAILURE() << e.path() << ": " << ex.what();
    }
  }
  EXPECT_GE(scenes, 15);
}

TEST(SceneSchema, ASectionTheSceneLeavesOutReadsAsItsDeclaredDefaults) {
  const auto c =
      config::load_config_text("wire: {}\ncontact:\n  friction: 0.3\n", "scene.yaml", coupling::scene_schema());
  EXPECT_EQ(&coupling::given_or_declared(c, "wire"), &c);
  EXPECT_EQ(&coupling::given_or_declared(c, "contact"), &c);
  EXPECT_EQ(c.where("contact.friction"), "scene.yaml:3: contact.friction");
  const auto& coupling = coupling::given_or_declared(c, "coupling");
  ASSERT_NE(&coupling, &c);
  EXPECT_EQ(coupling.string("coupling.drag"), coupling::scene_schema().find("coupling.drag")->default_text);
  EXPECT_EQ(coupling.where("coupling.drag"), "default: coupling.drag");
  EXPECT_FALSE(coupling.has_section("coupling.steering"));  // no default: absent
  EXPECT_FALSE(coupling.has_section("contact"));
  EXPECT_THROW((void)coupling::declared_scene_defaults("coupling.steering"), flowire::Error);  // not top-level
}

}  // namespace
