#include "flowire/rod/model.hpp"

#include <fmt/format.h>

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

}  // namespace

TipShape parse_tip_shape(std::string_view name) {
  if (name == "straight") return TipShape::Straight;
  if (name == "angled") return TipShape::Angled;
  if (name == "j" || name == "J") return TipShape::J;
  throw_usage_error("tip shape '" + std::string(name) + "': use straight, angled or j");
}

const char* to_string(TipShape shape) {
  switch (shape) {
    case TipShape::Straight:
      return "straight";
    case TipShape::Angled:
      return "angled";
    case TipShape::J:
      return "j";
  }
  return "straight";
}

RodModel RodModel::from_spec(const WireSpec& s) {
  require(s.length > 0.0, "length must be > 0");
  require(s.radius > 0.0 ||
              (s.bending_stiffness > 0 && s.stretch_stiffness > 0 && s.mass_per_length > 0 && s.twist_stiffness > 0),
          "radius must be > 0");
  require(s.youngs_modulus > 0.0, "youngs_modulus must be > 0");
  require(s.density > 0.0, "density must be > 0");
  require(s.poisson_ratio > -1.0 && s.poisson_ratio < 0.5, "poisson_ratio must be in (-1, 0.5)");
  require(s.segments > 0 || s.segment_length > 0.0, "give segments or a segment_length > 0");
  require(s.base_direction.norm() > 0.0, "base_direction must be nonzero");
  require(s.damping >= 0.0, "damping must be >= 0");
  require(s.mass_damping >= 0.0 && std::isfinite(s.mass_damping), "mass_damping must be >= 0");
  require(s.tip.length >= 0.0 && s.tip.bend_radius > 0.0, "tip length >= 0 and bend_radius > 0");

  RodModel m;
  m.length = s.length;
  m.h = s.segments > 0 ? s.length / s.segments : s.segment_length;
  require(m.h <= s.length, "segment_length longer than the wire");
  require(s.length / m.h <= kMaxRodSegments,
          fmt::format("length / segment_length = {:.3g} segments; a rod has at most {:.0e}", s.length / m.h,
                      kMaxRodSegments));
  m.grid_vertices = static_cast<int>(std::ceil(s.length / m.h - 1e-9)) + 3;
  m.base_position = s.base_position;
  m.base_direction = s.base_direction.normalized();
  Eigen::Vector3d n = s.base_normal - m.base_direction * m.base_direction.dot(s.base_normal);
  if (n.norm() < 1e-12) {
    const Eigen::Vector3d trial =
        std::abs(m.base_direction.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    n = trial - m.base_direction * m.base_direction.dot(trial);
  }
  m.base_normal = n.normalized();
  m.damping = s.damping;
  m.mass_damping = s.mass_damping;

  m.G_shaft_ = s.shear_modulus > 0.0 ? s.shear_modulus : s.youngs_modulus / (2.0 * (1.0 + s.poisson_ratio));
  m.E_shaft_ = s.youngs_modulus;
  m.E_tip_ = s.tip.youngs_modulus > 0.0 ? s.tip.youngs_modulus : s.youngs_modulus;
  m.r_shaft_ = s.radius;
  m.r_tip_ = s.tip.radius > 0.0 ? s.tip.radius : s.radius;
  m.nu_ = s.shear_modulus > 0.0 ? s.youngs_modulus / (2.0 * s.shear_modulus) - 1.0 : s.poisson_ratio;
  m.tip_length_ = s.tip.length;
  m.transition_ = s.tip.transition_length;
  m.ei_override_ = s.bending_stiffness;
  m.gj_override_ = s.twist_stiffness;
  m.ea_override_ = s.stretch_stiffness;
  m.rho_a_override_ = s.mass_per_length;
  m.density_ = s.density;

  // Rest curvature density 1/R on the pre-shaped arc [arc_begin, arc_end].
  m.arc_radius_ = s.tip.bend_radius;
  if (s.tip.shape != TipShape::Straight) {
    const bool j_shape = s.tip.shape == TipShape::J;
    const double angle = s.tip.angle >= 0.0 ? s.tip.angle : (j_shape ? std::numbers::pi : std::numbers::pi / 4.0);
    require(angle < 2.0 * std::numbers::pi, "tip angle must be < 2π");
    const double offset = s.tip.bend_offset >= 0.0 ? s.tip.bend_offset : (j_shape ? 0.0 : 0.002);
    // The distal half segment cannot bend (no vertex there): start the arc at h/2 at the
    // earliest so the whole angle is kept.
    m.arc_begin_ = std::max(offset, 0.5 * m.h);
    m.arc_end_ = m.arc_begin_ + angle * m.arc_radius_;
  }

  // Adaptivity defaults.
  m.adapt = s.adapt;
  if (m.adapt.min_segment_length <= 0.0) m.adapt.min_segment_length = 0.25 * m.h;
  if (m.adapt.max_segment_length <= 0.0) m.adapt.max_segment_length = m.h;
  if (m.adapt.merge_angle < 0.0) m.adapt.merge_angle = 0.25 * m.adapt.split_angle;
  if (m.adapt.enabled) {
    require(m.adapt.min_segment_length <= m.h && m.adapt.max_segment_length >= m.h,
            "adapt: min_segment_length <= segment length <= max_segment_length");
    require(m.adapt.split_angle > 0.0 && m.adapt.split_angle < 1.5, "adapt: split_angle must be in (0, 1.5) rad");
    require(m.adapt.merge_angle >= 0.0 && m.adapt.merge_angle < 0.5 * m.adapt.split_angle,
            "adapt: merge_angle must be below split_angle / 2 (hysteresis)");
  }

  // The uniform feeding grid.
  std::vector<double> u(static_cast<size_t>(m.grid_vertices));
  for (int k = 0; k < m.grid_vertices; ++k) u[static_cast<size_t>(k)] = m.u(k);
  m.reserve(m.grid_vertices);
  m.discretize(u, m);
  return m;
}

Section RodModel::section(double u) const {
  double w = 1.0;  // blend factor 0 (tip) → 1 (shaft)
  if (tip_length_ > 0.0) {
    if (transition_ <= 0.0) {
      w = u < tip_length_ ? 0.0 : 1.0;
    } else {
      w = std::clamp((u - (tip_length_ - 0.5 * transition_)) / transition_, 0.0, 1.0);
    }
  }
  const double E = (1.0 - w) * E_tip_ + w * E_shaft_;
  const double r = (1.0 - w) * r_tip_ + w * r_shaft_;
  const double G = E / (2.0 * (1.0 + nu_));  // equals G_shaft on the shaft
  const double A = std::numbers::pi * r * r;
  const double I = A * r * r / 4.0;
  // Overrides scale the profile so a softer tip keeps its ratio to the shaft.
  const double A_shaft = std::numbers::pi * r_shaft_ * r_shaft_;
  const double I_shaft = A_shaft * r_shaft_ * r_shaft_ / 4.0;
  Section c;
  c.bend_stiffness = ei_override_ > 0 ? ei_override_ * (E * I) / (E_shaft_ * I_shaft) : E * I;
  c.twist_stiffness = gj_override_ > 0 ? gj_override_ * (G * I) / (G_shaft_ * I_shaft) : G * 2.0 * I;
  c.stretch_stiffness = ea_override_ > 0 ? ea_override_ * (E * A) / (E_shaft_ * A_shaft) : E * A;
  c.rho_a = rho_a_override_ > 0 ? rho_a_override_ * A / A_shaft : density_ * A;
  c.radius = r;
  return c;
}

double RodModel::rest_turning(double a, double b) const {
  if (arc_end_ <= arc_begin_) return 0.0;
  return std::max(0.0, std::min(b, arc_end_) - std::max(a, arc_begin_)) / arc_radius_;
}

void Discretization::reserve(int vertices) {
  for (auto* v : {&rest_length, &stretch_stiffness, &rho_a, &twist_inertia, &edge_radius, &mass, &cell_length,
                  &bend_stiffness, &twist_stiffness, &rest_kappa1, &rest_kappa2})
    v->reserve(static_cast<size_t>(vertices));
}

void RodModel::discretize(const std::vector<double>& u, Discretization& d) const {
  const int nv = static_cast<int>(u.size());
  const int ne = std::max(nv - 1, 0);
  const auto ue = static_cast<size_t>(ne), uv = static_cast<size_t>(nv);
  d.rest_length.resize(ue);
  d.stretch_stiffness.resize(ue);
  d.rho_a.resize(ue);
  d.twist_inertia.resize(ue);
  d.edge_radius.resize(ue);
  d.mass.resize(uv);
  d.cell_length.resize(uv);
  d.bend_stiffness.resize(uv);
  d.twist_stiffness.resize(uv);
  d.rest_kappa1.resize(uv);
  d.rest_kappa2.resize(uv);
  // Edge constants at the midpoint; EI and GJ kept per edge in the vertex arrays' slots
  // until the vertex averages are formed (vertex k only reads edges k−1 and k).
  double ei_prev = 0.0, gj_prev = 0.0;
  for (int k = 0; k < nv; ++k) {
    const auto K = static_cast<size_t>(k);
    double ei = 0.0, gj = 0.0, len = 0.0;
    if (k < ne) {
      len = u[K + 1] - u[K];
      const Section c = section(0.5 * (u[K] + u[K + 1]));
      d.rest_length[K] = len;
      d.stretch_stiffness[K] = c.stretch_stiffness;
      d.rho_a[K] = c.rho_a;
      // Polar inertia per length ρJ = ρA r²/2.
      d.twist_inertia[K] = c.rho_a * c.radius * c.radius / 2.0 * len;
      d.edge_radius[K] = c.radius;
      ei = c.bend_stiffness;
      gj = c.twist_stiffness;
    }
    const double left = k > 0 ? d.rest_length[K - 1] : 0.0;
    const double right = len;
    d.cell_length[K] = 0.5 * (left + right);
    d.mass[K] = 0.5 * ((k > 0 ? d.rho_a[K - 1] * left : 0.0) + (k < ne ? d.rho_a[K] * right : 0.0));
    d.bend_stiffness[K] = d.twist_stiffness[K] = 0.0;
    d.rest_kappa1[K] = d.rest_kappa2[K] = 0.0;
    if (k > 0 && k < ne) {
      d.bend_stiffness[K] = (ei_prev * left + ei * right) / (left + right);
      d.twist_stiffness[K] = (gj_prev * left + gj * right) / (left + right);
      const double turn = rest_turning(u[K] - 0.5 * left, u[K] + 0.5 * right);
      d.rest_kappa1[K] = 2.0 * std::tan(0.5 * std::min(turn, 0.95 * std::numbers::pi));
    }
    ei_prev = ei;
    gj_prev = gj;
  }
}

}  // namespace flowire::rod
