#include "flowire/rod/model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "flowire/common/error.hpp"

namespace flowire::rod {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw_usage_error("WireSpec: " + what);
}

/// Blend factor 0 (tip) → 1 (shaft) at material coordinate u.
double shaft_fraction(const TipSpec& tip, double u) {
  if (tip.length <= 0.0) return 1.0;
  if (tip.transition_length <= 0.0) return u < tip.length ? 0.0 : 1.0;
  const double a = tip.length - 0.5 * tip.transition_length;
  return std::clamp((u - a) / tip.transition_length, 0.0, 1.0);
}

}  // namespace

TipShape parse_tip_shape(std::string_view name) {
  if (name == "straight") return TipShape::Straight;
  if (name == "angled") return TipShape::Angled;
  if (name == "j" || name == "J") return TipShape::J;
  throw_usage_error("tip shape '" + std::string(name) + "': use straight, angled or j");
}

const char* to_string(TipShape shape) {
  switch (shape) {
    case TipShape::Straight: return "straight";
    case TipShape::Angled: return "angled";
    case TipShape::J: return "j";
  }
  return "straight";
}

RodModel RodModel::from_spec(const WireSpec& s) {
  require(s.length > 0.0, "length must be > 0");
  require(s.radius > 0.0 || (s.bending_stiffness > 0 && s.stretch_stiffness > 0 &&
                             s.mass_per_length > 0 && s.twist_stiffness > 0),
          "radius must be > 0");
  require(s.youngs_modulus > 0.0, "youngs_modulus must be > 0");
  require(s.density > 0.0, "density must be > 0");
  require(s.poisson_ratio > -1.0 && s.poisson_ratio < 0.5, "poisson_ratio must be in (-1, 0.5)");
  require(s.segments > 0 || s.segment_length > 0.0, "give segments or a segment_length > 0");
  require(s.base_direction.norm() > 0.0, "base_direction must be nonzero");
  require(s.damping >= 0.0, "damping must be >= 0");
  require(s.tip.length >= 0.0 && s.tip.bend_radius > 0.0, "tip length >= 0 and bend_radius > 0");

  RodModel m;
  m.length = s.length;
  m.h = s.segments > 0 ? s.length / s.segments : s.segment_length;
  require(m.h <= s.length, "segment_length longer than the wire");
  m.grid_vertices = static_cast<int>(std::ceil(s.length / m.h - 1e-9)) + 3;
  m.base_position = s.base_position;
  m.base_direction = s.base_direction.normalized();
  Eigen::Vector3d n = s.base_normal - m.base_direction * m.base_direction.dot(s.base_normal);
  if (n.norm() < 1e-12) {
    const Eigen::Vector3d trial = std::abs(m.base_direction.z()) < 0.9 ? Eigen::Vector3d::UnitZ()
                                                                       : Eigen::Vector3d::UnitX();
    n = trial - m.base_direction * m.base_direction.dot(trial);
  }
  m.base_normal = n.normalized();
  m.damping = s.damping;

  const double G_shaft =
      s.shear_modulus > 0.0 ? s.shear_modulus : s.youngs_modulus / (2.0 * (1.0 + s.poisson_ratio));
  const double E_tip = s.tip.youngs_modulus > 0.0 ? s.tip.youngs_modulus : s.youngs_modulus;
  const double r_tip = s.tip.radius > 0.0 ? s.tip.radius : s.radius;
  const double nu = s.shear_modulus > 0.0 ? s.youngs_modulus / (2.0 * s.shear_modulus) - 1.0
                                          : s.poisson_ratio;

  const int nv = m.grid_vertices;
  const int ne = nv - 1;
  m.stretch_stiffness.assign(ne, 0.0);
  m.rho_a.assign(ne, 0.0);
  m.twist_inertia.assign(ne, 0.0);
  m.edge_radius.assign(ne, 0.0);
  std::vector<double> ei(ne), gj(ne);
  for (int j = 0; j < ne; ++j) {
    const double u = (j + 0.5) * m.h;
    const double w = shaft_fraction(s.tip, u);
    const double E = (1.0 - w) * E_tip + w * s.youngs_modulus;
    const double r = (1.0 - w) * r_tip + w * s.radius;
    const double G = E / (2.0 * (1.0 + nu));  // equals G_shaft on the shaft
    const double A = std::numbers::pi * r * r;
    const double I = std::numbers::pi * r * r * r * r / 4.0;
    // Overrides scale the profile so a softer tip keeps its ratio to the shaft.
    const double Ashaft = std::numbers::pi * s.radius * s.radius;
    const double Ishaft = Ashaft * s.radius * s.radius / 4.0;
    ei[j] = s.bending_stiffness > 0 ? s.bending_stiffness * (E * I) / (s.youngs_modulus * Ishaft) : E * I;
    gj[j] = s.twist_stiffness > 0 ? s.twist_stiffness * (G * I) / (G_shaft * Ishaft) : G * 2.0 * I;
    m.stretch_stiffness[j] =
        s.stretch_stiffness > 0 ? s.stretch_stiffness * (E * A) / (s.youngs_modulus * Ashaft) : E * A;
    m.rho_a[j] = s.mass_per_length > 0 ? s.mass_per_length * A / Ashaft : s.density * A;
    // Polar inertia per length ρJ = ρA r²/2.
    m.twist_inertia[j] = m.rho_a[j] * r * r / 2.0 * m.h;
    m.edge_radius[j] = r;
  }

  // Rest curvature density (1/R on the pre-shaped arc), integrated over Voronoi cells.
  double arc_begin = 0.0, arc_end = 0.0, R = s.tip.bend_radius;
  if (s.tip.shape != TipShape::Straight) {
    const bool j_shape = s.tip.shape == TipShape::J;
    const double angle = s.tip.angle >= 0.0 ? s.tip.angle
                                             : (j_shape ? std::numbers::pi : std::numbers::pi / 4.0);
    require(angle < 2.0 * std::numbers::pi, "tip angle must be < 2π");
    const double offset = s.tip.bend_offset >= 0.0 ? s.tip.bend_offset : (j_shape ? 0.0 : 0.002);
    // The distal half segment cannot bend (no vertex there): start the arc at h/2 at the
    // earliest so the whole angle is kept.
    arc_begin = std::max(offset, 0.5 * m.h);
    arc_end = arc_begin + angle * R;
  }
  m.mass.assign(nv, 0.0);
  m.bend_stiffness.assign(nv, 0.0);
  m.twist_stiffness.assign(nv, 0.0);
  m.rest_kappa1.assign(nv, 0.0);
  m.rest_kappa2.assign(nv, 0.0);
  for (int k = 0; k < nv; ++k) {
    const double left = k > 0 ? m.rho_a[k - 1] : 0.0;
    const double right = k < ne ? m.rho_a[k] : 0.0;
    m.mass[k] = 0.5 * (left + right) * m.h;
    if (k == 0 || k == ne) continue;
    m.bend_stiffness[k] = 0.5 * (ei[k - 1] + ei[k]);
    m.twist_stiffness[k] = 0.5 * (gj[k - 1] + gj[k]);
    if (arc_end > arc_begin) {
      const double a = std::max(arc_begin, (k - 0.5) * m.h);
      const double b = std::min(arc_end, (k + 0.5) * m.h);
      const double turn = std::max(0.0, b - a) / R;  // turning angle in this cell
      m.rest_kappa1[k] = 2.0 * std::tan(0.5 * std::min(turn, 0.95 * std::numbers::pi));
    }
  }
  return m;
}

}  // namespace flowire::rod
