#include "flowire/rod/loads.hpp"

#include <algorithm>
#include <cmath>

namespace flowire::rod {

void Gravity::add(const LoadSite& rod, double scale, LoadTerms& out) const {
  if (!(acceleration.squaredNorm() > 0.0)) return;
  for (size_t k = 0; k < rod.positions.size(); ++k)
    out.force.segment<3>(4 * static_cast<Eigen::Index>(k)) += scale * rod.mass[k] * acceleration;
}

double Gravity::force_scale(const LoadSite& rod, double scale, double /*length*/) const {
  double total_mass = 0.0;
  for (double m : rod.mass) total_mass += m;
  return scale * total_mass * acceleration.norm();
}

void TipForce::add(const LoadSite& /*rod*/, double scale, LoadTerms& out) const {
  out.force.segment<3>(0) += scale * force;
}

double TipForce::force_scale(const LoadSite& /*rod*/, double scale, double /*length*/) const {
  return scale * force.norm();
}

void PointForces::add(const LoadSite& rod, double scale, LoadTerms& out) const {
  const double L = rod.inserted_length;
  const int nv = static_cast<int>(rod.positions.size());
  for (const Point& pf : points) {
    const double u = L - pf.s;  // from the tip
    if (u < 0.0 || u > L) continue;
    const auto it = std::upper_bound(rod.material.begin(), rod.material.end(), u);
    const int k = std::clamp(static_cast<int>(it - rod.material.begin()) - 1, 0, nv - 2);
    const double a = std::clamp((u - rod.material[k]) / (rod.material[k + 1] - rod.material[k]), 0.0, 1.0);
    out.force.segment<3>(4 * k) += scale * (1.0 - a) * pf.f;
    out.force.segment<3>(4 * (k + 1)) += scale * a * pf.f;
  }
}

double PointForces::force_scale(const LoadSite& /*rod*/, double scale, double /*length*/) const {
  double f = 0.0;
  for (const Point& pf : points) f = std::max(f, scale * pf.f.norm());
  return f;
}

void TipMoment::add(const LoadSite& rod, double scale, LoadTerms& out) const {
  if (!(moment.squaredNorm() > 0.0)) return;
  const Vec3 M = scale * moment;
  const Vec3 e = rod.positions[1] - rod.positions[0];
  const double l2 = e.squaredNorm();
  const Vec3 t = e / std::sqrt(l2);
  out.force(3) += M.dot(t);
  const Vec3 Mp = M - t * t.dot(M);
  const Vec3 f1 = Mp.cross(e) / l2;  // couple: e × f1 = M⊥
  out.force.segment<3>(4) += f1;
  out.force.segment<3>(0) -= f1;
  Mat3 skewM;
  skewM << 0, -Mp.z(), Mp.y(), Mp.z(), 0, -Mp.x(), -Mp.y(), Mp.x(), 0;
  const Mat3 k = skewM / l2 - 2.0 * f1 * e.transpose() / l2;
  out.tip_edge_stiffness = -0.5 * (k + k.transpose());
}

double TipMoment::force_scale(const LoadSite& /*rod*/, double scale, double length) const {
  return scale * moment.norm() / length;
}

void Loads::add(const LoadSite& rod, double scale, LoadTerms& out) const {
  gravity.add(rod, scale, out);
  tip_force.add(rod, scale, out);
  point_forces.add(rod, scale, out);
  tip_moment.add(rod, scale, out);
}

double Loads::force_scale(const LoadSite& rod, double scale, double length, double f) const {
  return std::max({f, gravity.force_scale(rod, scale, length), tip_force.force_scale(rod, scale, length),
                   tip_moment.force_scale(rod, scale, length), point_forces.force_scale(rod, scale, length)});
}

}  // namespace flowire::rod
