// The user's loads, each alone: what each adds to the generalized force (totals, where a point
// force lands, the couple of a tip moment), its stiffness against central differences of its
// force, and the force scale each reports.
#include "flowire/rod/loads.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "flowire_test.hpp"

using namespace flowire::rod;

namespace {

/// A bent five-vertex rod: positions, material coordinates from the tip, masses.
struct Site {
  std::vector<Vec3> x = {
      {0, 0, 0}, {1e-3, 0.2e-3, 0}, {2e-3, 0.3e-3, 0.1e-3}, {3e-3, 0.3e-3, 0.3e-3}, {4e-3, 0, 0.3e-3}};
  std::vector<double> u = {0, 1e-3, 2e-3, 3e-3, 4e-3};
  std::vector<double> m = {1e-6, 2e-6, 2e-6, 2e-6, 1e-6};
  double inserted = 3.5e-3;  // the last vertex behind the entry
  LoadSite site() const { return {x, u, m, inserted}; }
};

struct Out {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(4 * 5 - 1);
  Mat3 k = Mat3::Zero();
};

template <class L>
Out apply(const L& load, const LoadSite& site, double scale) {
  Out o;
  LoadTerms terms{o.f, o.k};
  load.add(site, scale, terms);
  return o;
}

Vec3 total_force(const Eigen::VectorXd& f) {
  Vec3 sum = Vec3::Zero();
  for (int k = 0; 4 * k + 2 < f.size(); ++k) sum += f.segment<3>(4 * k);
  return sum;
}

}  // namespace

TEST(Loads, GravityWeighsEveryVertexAndATipForceOnlyTheTip) {
  Site s;
  Gravity g;
  g.acceleration = Vec3(0, 0, -9.81);
  const auto o = apply(g, s.site(), 0.5);
  EXPECT_LT((total_force(o.f) - 0.5 * 8e-6 * g.acceleration).norm(), 1e-18);
  for (int k = 0; k < 5; ++k) EXPECT_LT((o.f.segment<3>(4 * k) - 0.5 * s.m[k] * g.acceleration).norm(), 1e-20);
  EXPECT_NEAR(g.force_scale(s.site(), 0.5, 1.0), 0.5 * 8e-6 * 9.81, 1e-18);
  TipForce t;
  t.force = Vec3(1, 2, 3);
  const auto ot = apply(t, s.site(), 2.0);
  EXPECT_EQ(Vec3(ot.f.segment<3>(0)), Vec3(2, 4, 6));
  EXPECT_EQ(ot.f.tail(ot.f.size() - 3).norm(), 0.0);
  EXPECT_DOUBLE_EQ(t.force_scale(s.site(), 2.0, 1.0), 2.0 * std::sqrt(14.0));
}

TEST(Loads, APointForceIsSharedByTheTwoVerticesAroundItsMaterialPoint) {
  Site s;
  PointForces p;
  const Vec3 f(0.3, -0.1, 0.2);
  p.points = {{1.2e-3, f}, {5e-3, Vec3(1, 1, 1)}};  // the second lies beyond the tip: no force
  const auto o = apply(p, s.site(), 1.0);
  EXPECT_LT((total_force(o.f) - f).norm(), 1e-15);
  // The shares' centre in the material coordinate is the point's: u = L − s = 2.3 mm.
  double centre = 0.0, weight = 0.0;
  for (int k = 0; k < 5; ++k) {
    const double w = o.f.segment<3>(4 * k).dot(f) / f.squaredNorm();
    EXPECT_GE(w, -1e-15);
    centre += w * s.u[k];
    weight += w;
  }
  EXPECT_NEAR(centre / weight, 2.3e-3, 1e-15);
  EXPECT_NEAR(p.force_scale(s.site(), 3.0, 1.0), 3.0 * std::sqrt(3.0), 1e-15);
}

TEST(Loads, ATipMomentIsATwistAndACoupleWhoseStiffnessIsItsForcesDerivative) {
  Site s;
  TipMoment t;
  t.moment = Vec3(2e-4, -1e-4, 3e-4);
  const auto o = apply(t, s.site(), 0.8);
  const Vec3 e = s.x[1] - s.x[0];
  const Vec3 tan = e.normalized();
  const Vec3 M = 0.8 * t.moment;
  EXPECT_NEAR(o.f(3), M.dot(tan), 1e-18);  // the twist about the edge
  const Vec3 f0 = o.f.segment<3>(0), f1 = o.f.segment<3>(4);
  EXPECT_LT((f0 + f1).norm(), 1e-18);                               // a couple: no net force
  EXPECT_LT((e.cross(f1) - (M - M.dot(tan) * tan)).norm(), 1e-18);  // whose moment is M⊥
  // −∂f₁/∂e, symmetrized, against central differences of f₁ in e (moving x₁).
  Eigen::Matrix3d J;
  const double h = 1e-9;
  for (int c = 0; c < 3; ++c) {
    Site p = s, m = s;
    p.x[1][c] += h;
    m.x[1][c] -= h;
    J.col(c) = (apply(t, p.site(), 0.8).f.segment<3>(4) - apply(t, m.site(), 0.8).f.segment<3>(4)) / (2 * h);
  }
  const Mat3 K = -0.5 * (J + J.transpose());
  EXPECT_LT((o.k - K).norm(), 1e-6 * K.norm());
  EXPECT_NEAR(t.force_scale(s.site(), 0.8, 0.1), 0.8 * t.moment.norm() / 0.1, 1e-15);
}

TEST(Loads, LoadsSumsEachKindAndTakesTheLargestForceScale) {
  Site s;
  Loads all;
  all.gravity.acceleration = Vec3(0, -9.81, 0);
  all.tip_force.force = Vec3(0.01, 0, 0);
  all.point_forces.points = {{2e-3, Vec3(0, 0, 0.02)}};
  all.tip_moment.moment = Vec3(0, 0, 1e-5);
  const auto o = apply(all, s.site(), 1.0);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(o.f.size());
  for (const Load* l :
       std::initializer_list<const Load*>{&all.gravity, &all.tip_force, &all.point_forces, &all.tip_moment})
    sum += apply(*l, s.site(), 1.0).f;
  EXPECT_LT((o.f - sum).norm(), 1e-18);
  EXPECT_EQ(o.k, apply(all.tip_moment, s.site(), 1.0).k);
  EXPECT_DOUBLE_EQ(all.force_scale(s.site(), 1.0, 1e-3, 0.0), 0.02);
  EXPECT_DOUBLE_EQ(all.force_scale(s.site(), 1.0, 1e-3, 0.5), 0.5);
}
