// Domains built in code (flow/fem/src/shape_domain.cpp): an invalid domain is an input
// error that names the domain.
#include <gtest/gtest.h>

#include <string>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/fem/shape_domain.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

using Kind = BoundaryGroup::Kind;
using test::tube_with_wire;

TEST(FemForces, DomainErrorsNameTheDomain) {
  ShapeDomain d = tube_with_wire(1e-3, 4e-3, 0.0, 0.5e-3, 0.0);
  d.groups[0].kind = Kind::Inlet;
  EXPECT_THROW(build_mesh(d), Error);
  d = tube_with_wire(1e-3, 4e-3, 0.0, 0.5e-3, 0.0);
  d.outer.face_group[2] = 7;
  try {
    build_mesh(d);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("tube with a wire"), std::string::npos) << e.what();
  }
  d = tube_with_wire(1e-3, 4e-3, 0.0, 0.5e-3, 0.0);
  d.groups.push_back({Kind::Wall, -1, "unused"});
  EXPECT_THROW(build_mesh(d), Error);  // a group without a face
}

}  // namespace
}  // namespace flowire::flow::fem
