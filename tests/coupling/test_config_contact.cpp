// The contact: section (coupling/src/config_contact.cpp): its keys and the wall contact they
// set, from the scene or, where it has no contact:, from the declared defaults.
#include <gtest/gtest.h>

#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

TEST(ConfigContact, DeclaresTheContactKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_contact_keys), {"contact"});
}

TEST(ConfigContact, ValuesGivenInTheSceneAreRead) {
  const auto k =
      contact_settings(test::scene("contact: {enabled: false, stiffness: 2e3, friction: 0.3, tip_friction: 0.05, "
                                   "viscous_friction: 4, onset: 0.1 mm, settle: false,\n"
                                   "          allow_outside: true, introducer: false}\n"));
  EXPECT_FALSE(k.params.enabled);
  EXPECT_DOUBLE_EQ(k.params.stiffness, 2e3);
  EXPECT_DOUBLE_EQ(k.params.friction, 0.3);
  EXPECT_DOUBLE_EQ(k.params.tip_friction, 0.05);
  EXPECT_DOUBLE_EQ(k.params.viscous_friction, 4.0);
  EXPECT_DOUBLE_EQ(k.params.onset, 1e-4);
  EXPECT_FALSE(k.settle);
  EXPECT_TRUE(k.allow_outside);
  EXPECT_FALSE(k.introducer);
  // The tip's friction is the shaft's unless given.
  EXPECT_DOUBLE_EQ(contact_settings(test::scene("contact: {friction: 0.4}\n")).params.tip_friction, 0.4);
}

TEST(ConfigContact, WithoutAContactSectionTheDeclaredDefaultsApply) {
  const auto absent = contact_settings(test::scene(""));
  const auto empty = contact_settings(test::scene("contact: {}\n"));
  // The values of the declaration (coupling/src/config_contact.cpp), as written there.
  EXPECT_TRUE(absent.params.enabled);
  EXPECT_DOUBLE_EQ(absent.params.stiffness, 3e4);
  EXPECT_DOUBLE_EQ(absent.params.friction, 0.1);
  EXPECT_DOUBLE_EQ(absent.params.tip_friction, 0.1);
  EXPECT_DOUBLE_EQ(absent.params.viscous_friction, 0.0);
  // The onset: 0.2 of the wire's radius (the declared 0.45 mm, or the scene's own).
  EXPECT_DOUBLE_EQ(absent.params.onset, 0.2 * 0.45e-3);
  EXPECT_DOUBLE_EQ(contact_settings(test::scene("wire: {radius: 0.3 mm}\n")).params.onset, 0.2 * 0.3e-3);
  EXPECT_TRUE(absent.settle);
  EXPECT_FALSE(absent.allow_outside);
  EXPECT_TRUE(absent.introducer);
  // And the same as a scene that writes the section empty.
  EXPECT_EQ(absent.params.stiffness, empty.params.stiffness);
  EXPECT_EQ(absent.params.friction, empty.params.friction);
  EXPECT_EQ(absent.settle, empty.settle);
  EXPECT_EQ(absent.introducer, empty.introducer);
}

TEST(ConfigContact, ABadValueIsRejectedAtLoadNamingFileLineAndKey) {
  const std::string e = test::input_error([] { (void)test::scene("contact:\n  stiffness: stiff\n"); });
  EXPECT_NE(e.find("scene.yaml:2: contact.stiffness"), std::string::npos) << e;
}

}  // namespace
}  // namespace flowire::coupling
