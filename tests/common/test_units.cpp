#include "flowire/common/units.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "flowire/common/error.hpp"
#include "flowire_test.hpp"

using flowire::units::Dimension;
using flowire::units::parse_quantity;

TEST(Units, PlainNumbersAreSI) {
  EXPECT_DOUBLE_EQ(parse_quantity("13000", Dimension::Pressure, "x"), 13000.0);
  EXPECT_DOUBLE_EQ(parse_quantity(" 3.5e-3 ", Dimension::Viscosity, "x"), 3.5e-3);
}

TEST(Units, ConvertsEachDimension) {
  EXPECT_DOUBLE_EQ(parse_quantity("5 mm", Dimension::Length, "x"), 5e-3);
  EXPECT_DOUBLE_EQ(parse_quantity("2 cm", Dimension::Length, "x"), 2e-2);
  EXPECT_DOUBLE_EQ(parse_quantity("120 mmHg", Dimension::Pressure, "x"), 120 * 133.322387415);
  EXPECT_DOUBLE_EQ(parse_quantity("60 GPa", Dimension::Pressure, "x"), 60e9);
  EXPECT_DOUBLE_EQ(parse_quantity("3.5 cP", Dimension::Viscosity, "x"), 3.5e-3);
  EXPECT_DOUBLE_EQ(parse_quantity("10 ms", Dimension::Time, "x"), 1e-2);
  EXPECT_DOUBLE_EQ(parse_quantity("5 mL/s", Dimension::FlowRate, "x"), 5e-6);
  EXPECT_DOUBLE_EQ(parse_quantity("180 deg", Dimension::Angle, "x"), std::numbers::pi);
  EXPECT_DOUBLE_EQ(parse_quantity("2 turns/s", Dimension::AngularSpeed, "x"), 4 * std::numbers::pi);
  EXPECT_DOUBLE_EQ(parse_quantity("1.5 cm/s", Dimension::Velocity, "x"), 0.015);
  EXPECT_DOUBLE_EQ(parse_quantity("72 bpm", Dimension::Frequency, "x"), 1.2);
}

TEST(Units, WrongDimensionNamesBothDimensions) {
  try {
    parse_quantity("5 mmHg", Dimension::Length, "scene.yaml:3: wire.radius");
    FAIL() << "expected an error";
  } catch (const flowire::Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("scene.yaml:3: wire.radius"), std::string::npos) << msg;
    EXPECT_NE(msg.find("pressure"), std::string::npos) << msg;
    EXPECT_NE(msg.find("length"), std::string::npos) << msg;
    EXPECT_EQ(e.kind(), flowire::ErrorKind::Input);
  }
}

TEST(Units, RejectsGarbageUnknownUnitsAndNonFinite) {
  EXPECT_THROW(parse_quantity("abc", Dimension::Length, "x"), flowire::Error);
  EXPECT_THROW(parse_quantity("5 furlongs", Dimension::Length, "x"), flowire::Error);
  EXPECT_THROW(parse_quantity("nan", Dimension::Length, "x"), flowire::Error);
  EXPECT_THROW(parse_quantity("inf mm", Dimension::Length, "x"), flowire::Error);
  EXPECT_THROW(parse_quantity("3 mm", Dimension::None, "x"), flowire::Error);
}
