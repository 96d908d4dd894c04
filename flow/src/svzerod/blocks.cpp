#include "flowire/flow/svzerod/blocks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "flowire/common/error.hpp"

namespace flowire::flow::svzerod {

using json = nlohmann::json;

// ---------------------------------------------------------------- BlockInput

BlockInput::BlockInput(const json& values, std::string file, std::string block, double& period)
    : values_(values), file_(std::move(file)), block_(std::move(block)), period_(period) {
  if (!values_.is_object()) fail("the parameters must be a JSON object");
}

void BlockInput::fail(const std::string& what) const {
  throw_input_error(file_, fmt::format("block '{}': {}", block_, what));
}

Param BlockInput::param(const std::string& key) {
  asked_.push_back(key);
  if (!values_.contains(key)) fail(fmt::format("parameter '{}' is missing", key));
  const json& x = values_.at(key);
  if (x.is_number()) return Param(x.get<double>());
  if (!x.is_array() || x.empty()) fail(fmt::format("parameter '{}' must be a number or a list", key));
  for (const auto& e : x)
    if (!e.is_number()) fail(fmt::format("parameter '{}' must be a number or a list of numbers", key));
  auto v = x.get<std::vector<double>>();
  if (v.size() == 1) return Param(v[0]);
  if (!values_.contains("t") || !values_.at("t").is_array())
    fail(fmt::format("the list '{}' needs a time list 't'", key));
  auto t = values_.at("t").get<std::vector<double>>();
  if (t.size() != v.size()) fail(fmt::format("'{}' has {} values but 't' has {}", key, v.size(), t.size()));
  for (size_t i = 1; i < t.size(); ++i)
    if (!(t[i] > t[i - 1])) fail("times 't' must increase");
  Param p(std::move(t), std::move(v));
  if (period_ > 0.0 && p.cycle() != period_)
    throw_input_error(
        file_, fmt::format("inconsistent cardiac cycle period defined in parameters ({} and {})", period_, p.cycle()));
  period_ = p.cycle();
  any_table_ = true;
  return p;
}

Param BlockInput::param(const std::string& key, double fallback) {
  if (!values_.contains(key)) {
    asked_.push_back(key);
    return Param(fallback);
  }
  return param(key);
}

std::vector<double> BlockInput::numbers(const std::string& key) {
  asked_.push_back(key);
  if (!values_.contains(key)) fail(fmt::format("list '{}' is missing", key));
  const json& x = values_.at(key);
  if (!x.is_array()) fail(fmt::format("'{}' must be a list of numbers", key));
  std::vector<double> out;
  for (const auto& e : x) {
    if (!e.is_number()) fail(fmt::format("'{}' must be a list of numbers", key));
    out.push_back(e.get<double>());
  }
  return out;
}

void BlockInput::require_nonnegative(const std::string& key) const {
  if (!values_.contains(key)) return;
  const json& x = values_.at(key);
  for (const json& e : x.is_array() ? x : json::array({x}))
    if (const double v = e.get<double>(); !(v >= 0.0))
      fail(fmt::format("parameter '{}' = {}: must not be negative (>= 0)", key, v));
}

Param BlockInput::nonnegative(const std::string& key) {
  Param p = param(key);
  require_nonnegative(key);
  return p;
}

Param BlockInput::nonnegative(const std::string& key, double fallback) {
  Param p = param(key, fallback);
  require_nonnegative(key);
  return p;
}

std::vector<double> BlockInput::nonnegative_numbers(const std::string& key) {
  auto v = numbers(key);
  require_nonnegative(key);
  return v;
}

bool BlockInput::flag(const std::string& key, bool fallback) {
  asked_.push_back(key);
  if (!values_.contains(key)) return fallback;
  if (!values_.at(key).is_boolean()) fail(fmt::format("'{}' must be true or false", key));
  return values_.at(key).get<bool>();
}

void BlockInput::finish() const {
  for (const auto& [k, v] : values_.items()) {
    (void)v;
    if (k == "t" || (!k.empty() && k[0] == '_')) continue;
    if (std::find(asked_.begin(), asked_.end(), k) == asked_.end()) fail(fmt::format("unknown parameter '{}'", k));
  }
}

// ---------------------------------------------------------------- Registry

namespace {
const char* section_name(Section s) {
  switch (s) {
    case Section::Vessel:
      return "vessel";
    case Section::BoundaryCondition:
      return "boundary condition";
    case Section::Junction:
      return "junction";
  }
  return "block";
}

template <class T>
Registry::Factory make() {
  return [](BlockInput& in) -> std::unique_ptr<Block> {
    auto b = std::make_unique<T>(in);
    in.finish();
    return b;
  };
}

std::string one_connection(const Block& b) {
  const size_t n = b.inlets().size() + b.outlets().size();
  if (n == 1) return {};
  return fmt::format("boundary condition '{}' is connected {} times (needs 1)", b.name(), n);
}

std::string one_in_one_out(const Block& b) {
  if (b.inlets().size() == 1 && b.outlets().size() == 1) return {};
  return fmt::format("vessel '{}' must have one inlet and one outlet connection (has {} and {})", b.name(),
                     b.inlets().size(), b.outlets().size());
}

/// Sign of x: −1, 0, 1.
double sign(double x) { return static_cast<double>((0.0 < x) - (x < 0.0)); }
}  // namespace

Registry::Registry() {
  add(Section::Vessel, "BloodVessel", make<BloodVessel>());
  add(Section::Vessel, "BloodVesselCRL", make<BloodVesselCRL>());
  add(Section::BoundaryCondition, "FLOW", make<FlowBC>());
  add(Section::BoundaryCondition, "PRESSURE", make<PressureBC>());
  add(Section::BoundaryCondition, "RESISTANCE", make<ResistanceBC>());
  add(Section::BoundaryCondition, "RCR", make<RcrBC>());
  add(Section::BoundaryCondition, "CORONARY", [](BlockInput& in) -> std::unique_ptr<Block> {
    auto b = std::make_unique<CoronaryBC>(in, false);
    in.finish();
    return b;
  });
  add(Section::BoundaryCondition, "CORONARY_VAR_RES", [](BlockInput& in) -> std::unique_ptr<Block> {
    auto b = std::make_unique<CoronaryBC>(in, true);
    in.finish();
    return b;
  });
  add(Section::Junction, "NORMAL_JUNCTION", make<Junction>());
  add(Section::Junction, "BloodVesselJunction", make<BloodVesselJunction>());
}

const Registry& Registry::instance() {
  static const Registry r;
  return r;
}

void Registry::add(Section s, std::string type, Factory f) { entries_.push_back({s, std::move(type), std::move(f)}); }

bool Registry::has(Section section, const std::string& type) const {
  return std::any_of(entries_.begin(), entries_.end(),
                     [&](const Entry& e) { return e.section == section && e.type == type; });
}

std::string Registry::supported(Section section) const {
  std::string out;
  for (const auto& e : entries_)
    if (e.section == section) out += (out.empty() ? "" : ", ") + e.type;
  return out;
}

std::unique_ptr<Block> Registry::create(Section section, const std::string& type, BlockInput& in) const {
  for (const auto& e : entries_)
    if (e.section == section && e.type == type) return e.make(in);
  in.fail(
      fmt::format("{} type '{}' is not supported (supported: {})", section_name(section), type, supported(section)));
}

// ---------------------------------------------------------------- vessels

BloodVessel::BloodVessel(BlockInput& in)
    : Block(in.name()),
      r_(in.nonnegative("R_poiseuille")),
      c_(in.nonnegative("C", 0.0)),
      l_(in.nonnegative("L", 0.0)),
      s_(in.nonnegative("stenosis_coefficient", 0.0)) {
  time_dependent_ = in.any_table();
}

std::string BloodVessel::check_connections() const { return one_in_one_out(*this); }

void BloodVessel::assemble(Assembler& a, double t) const {
  const bool st = a.steady();
  const Node &i = inlets_[0], &o = outlets_[0];
  const double r = r_.get(t, st), c = c_.get(t, st), l = l_.get(t, st);
  a.f(row0_, i.p, 1.0);
  a.f(row0_, i.q, -r);
  a.f(row0_, o.p, -1.0);
  a.e(row0_, o.q, -l);
  a.c(row0_, 0.0);
  a.f(row0_ + 1, i.q, 1.0);
  a.f(row0_ + 1, o.q, -1.0);
  a.e(row0_ + 1, i.p, -c);
  a.e(row0_ + 1, i.q, c * r);
  a.c(row0_ + 1, 0.0);
}

void BloodVessel::assemble_nonlinear(Assembler& a, double t, const Eigen::VectorXd& y,
                                     const Eigen::VectorXd& yd) const {
  const bool st = a.steady();
  const Node& i = inlets_[0];
  const double s = s_.get(t, st), c = c_.get(t, st);
  const double q = y[i.q], aq = std::abs(q), qd = yd[i.q];
  // row 0: −S|Q_in|Q_in
  a.c_nl(row0_, -s * aq * q);
  a.dy(row0_, i.q, -2.0 * s * aq);
  // row 1: C d/dt(S|Q_in|Q_in) = 2 C S |Q_in| Q̇_in
  a.c_nl(row0_ + 1, 2.0 * s * c * aq * qd);
  a.dy(row0_ + 1, i.q, 2.0 * s * c * sign(q) * qd);
  a.dyd(row0_ + 1, i.q, 2.0 * s * c * aq);
}

BloodVesselCRL::BloodVesselCRL(BlockInput& in)
    : Block(in.name()),
      r_(in.nonnegative("R_poiseuille")),
      c_(in.nonnegative("C", 0.0)),
      l_(in.nonnegative("L", 0.0)),
      s_(in.nonnegative("stenosis_coefficient", 0.0)) {
  time_dependent_ = in.any_table();
}

std::string BloodVesselCRL::check_connections() const { return one_in_one_out(*this); }

void BloodVesselCRL::assemble(Assembler& a, double t) const {
  const bool st = a.steady();
  const Node &i = inlets_[0], &o = outlets_[0];
  a.f(row0_, i.p, 1.0);
  a.f(row0_, o.q, -r_.get(t, st));
  a.f(row0_, o.p, -1.0);
  a.e(row0_, o.q, -l_.get(t, st));
  a.c(row0_, 0.0);
  a.f(row0_ + 1, i.q, 1.0);
  a.f(row0_ + 1, o.q, -1.0);
  a.e(row0_ + 1, i.p, -c_.get(t, st));
  a.c(row0_ + 1, 0.0);
}

void BloodVesselCRL::assemble_nonlinear(Assembler& a, double t, const Eigen::VectorXd& y,
                                        const Eigen::VectorXd& /*yd*/) const {
  const Node& o = outlets_[0];
  const double s = s_.get(t, a.steady()), q = y[o.q], aq = std::abs(q);
  a.c_nl(row0_, -s * aq * q);
  a.dy(row0_, o.q, -2.0 * s * aq);
  a.c_nl(row0_ + 1, 0.0);
}

// ---------------------------------------------------------------- junctions

Junction::Junction(BlockInput& in) : Block(in.name()) {}

std::string Junction::check_connections() const {
  if (inlets_.empty() || outlets_.empty()) return fmt::format("junction '{}' needs inlets and outlets", name_);
  return {};
}

bool Junction::shared_pressure() const {
  const int p = inlets_.empty() ? -1 : inlets_[0].p;
  auto same = [&](const Node& n) { return n.p == p; };
  return std::all_of(inlets_.begin(), inlets_.end(), same) && std::all_of(outlets_.begin(), outlets_.end(), same);
}

int Junction::num_equations() const {
  return shared_pressure() ? 1 : static_cast<int>(inlets_.size() + outlets_.size());
}

void Junction::assemble(Assembler& a, double /*t*/) const {
  const int n = num_equations();
  auto node = [&](int k) -> const Node& {
    const auto ni = static_cast<int>(inlets_.size());
    return k < ni ? inlets_[static_cast<size_t>(k)] : outlets_[static_cast<size_t>(k - ni)];
  };
  for (int k = 1; k < n; ++k) {
    a.f(row0_ + k - 1, node(0).p, 1.0);
    a.f(row0_ + k - 1, node(k).p, -1.0);
    a.c(row0_ + k - 1, 0.0);
  }
  const int last = row0_ + n - 1;
  for (const auto& nd : inlets_) a.f(last, nd.q, 1.0);
  for (const auto& nd : outlets_) a.f(last, nd.q, -1.0);
  a.c(last, 0.0);
}

BloodVesselJunction::BloodVesselJunction(BlockInput& in)
    : Block(in.name()),
      r_(in.nonnegative_numbers("R_poiseuille")),
      l_(in.nonnegative_numbers("L")),
      s_(in.nonnegative_numbers("stenosis_coefficient")) {}

std::string BloodVesselJunction::check_connections() const {
  if (inlets_.size() != 1) return fmt::format("junction '{}': a BloodVesselJunction has exactly one inlet", name_);
  const size_t n = outlets_.size();
  if (r_.size() != n || l_.size() != n || s_.size() != n)
    return fmt::format("junction '{}': R_poiseuille, L and stenosis_coefficient need one value per outlet ({})", name_,
                       n);
  return {};
}

bool BloodVesselJunction::nonlinear() const {
  return std::any_of(s_.begin(), s_.end(), [](double s) { return s != 0.0; });
}

void BloodVesselJunction::assemble(Assembler& a, double /*t*/) const {
  const Node& i = inlets_[0];
  a.f(row0_, i.q, 1.0);
  for (const auto& o : outlets_) a.f(row0_, o.q, -1.0);
  a.c(row0_, 0.0);
  for (size_t k = 0; k < outlets_.size(); ++k) {
    const int row = row0_ + 1 + static_cast<int>(k);
    const Node& o = outlets_[k];
    a.f(row, i.p, 1.0);
    a.f(row, o.p, -1.0);
    a.f(row, o.q, -r_[k]);
    a.e(row, o.q, -l_[k]);
    a.c(row, 0.0);
  }
}

void BloodVesselJunction::assemble_nonlinear(Assembler& a, double /*t*/, const Eigen::VectorXd& y,
                                             const Eigen::VectorXd& /*yd*/) const {
  a.c_nl(row0_, 0.0);
  for (size_t k = 0; k < outlets_.size(); ++k) {
    const int row = row0_ + 1 + static_cast<int>(k);
    const Node& o = outlets_[k];
    const double q = y[o.q], aq = std::abs(q);
    a.c_nl(row, -s_[k] * aq * q);
    a.dy(row, o.q, -2.0 * s_[k] * aq);
  }
}

// ---------------------------------------------------------------- boundary conditions

FlowBC::FlowBC(BlockInput& in) : Block(in.name()), q_(in.param("Q")) { time_dependent_ = in.any_table(); }
std::string FlowBC::check_connections() const { return one_connection(*this); }
void FlowBC::assemble(Assembler& a, double t) const {
  a.f(row0_, port().q, 1.0);
  a.c(row0_, -q_.get(t, a.steady()));
}

PressureBC::PressureBC(BlockInput& in) : Block(in.name()), p_(in.param("P")) { time_dependent_ = in.any_table(); }
std::string PressureBC::check_connections() const { return one_connection(*this); }
void PressureBC::assemble(Assembler& a, double t) const {
  a.f(row0_, port().p, 1.0);
  a.c(row0_, -p_.get(t, a.steady()));
}

ResistanceBC::ResistanceBC(BlockInput& in) : Block(in.name()), r_(in.nonnegative("R")), pd_(in.param("Pd", 0.0)) {
  time_dependent_ = in.any_table();
}
std::string ResistanceBC::check_connections() const { return one_connection(*this); }
void ResistanceBC::assemble(Assembler& a, double t) const {
  a.f(row0_, port().p, 1.0);
  a.f(row0_, port().q, -r_.get(t, a.steady()));
  a.c(row0_, -pd_.get(t, a.steady()));
}

RcrBC::RcrBC(BlockInput& in)
    : Block(in.name()),
      rp_(in.nonnegative("Rp")),
      c_(in.nonnegative("C")),
      rd_(in.nonnegative("Rd")),
      pd_(in.param("Pd", 0.0)) {
  time_dependent_ = in.any_table();
}
std::string RcrBC::check_connections() const { return one_connection(*this); }
void RcrBC::assemble(Assembler& a, double t) const {
  const bool st = a.steady();
  const Node& n = port();
  const int pc = internal0_;
  const double rd = rd_.get(t, st), c = st ? 0.0 : c_.get(t, st);
  a.f(row0_, n.p, 1.0);
  a.f(row0_, n.q, -rp_.get(t, st));
  a.f(row0_, pc, -1.0);
  a.c(row0_, 0.0);
  a.f(row0_ + 1, n.q, rd);
  a.f(row0_ + 1, pc, -1.0);
  a.e(row0_ + 1, pc, -rd * c);
  a.c(row0_ + 1, pd_.get(t, st));
}

CoronaryBC::CoronaryBC(BlockInput& in, bool variable_resistance)
    : Block(in.name()),
      varres_(variable_resistance),
      ra_(in.nonnegative("Ra1")),
      rv_(in.nonnegative("Rv1")),
      ca_(in.nonnegative("Ca")),
      cim_(in.nonnegative("Cc")),
      pim_(in.param("Pim")),
      pv_(in.param("P_v")) {
  if (varres_) {
    ram_min_ = in.nonnegative("Ra2_min");
    ram_max_ = in.nonnegative("Ra2_max");
    t_vc_ = in.nonnegative("T_vc");
    t_vr_ = in.nonnegative("T_vr");
  } else {
    ram_ = in.nonnegative("Ra2");
  }
  if (in.flag("closed_loop_outlet", false)) in.fail("closed-loop coronary outlets are not supported");
  time_dependent_ = varres_ || in.any_table();
}

std::string CoronaryBC::check_connections() const { return one_connection(*this); }

double CoronaryBC::ram(double t, bool steady, double period) const {
  if (!varres_) return ram_.get(t, steady);
  const double lo = std::sqrt(ram_min_.get(t, steady)), hi = std::sqrt(ram_max_.get(t, steady));
  const double tvc = t_vc_.get(t, steady), tvr = t_vr_.get(t, steady);
  const double tc = std::fmod(t, period);
  double e = 0.0;
  if (tc <= tvc)
    e = 0.5 * (1.0 - std::cos(std::numbers::pi * tc / tvc));
  else if (tc <= tvc + tvr)
    e = 0.5 * (1.0 + std::cos(std::numbers::pi * (tc - tvc) / tvr));
  const double r = lo + (hi - lo) * e;
  return r * r;
}

void CoronaryBC::prepare(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, bool after_steady, double period) {
  const Node& n = port();
  const double ra = ra_.get(0.0), ca = ca_.get(0.0), ram0 = ram(0.0, false, period);
  const double p_ca = y[n.p] - ra * y[n.q];
  const double p_ca_dot = yd[n.p] - ra * yd[n.q];
  const double q_am = y[n.q] - ca * p_ca_dot;
  pcim0_ = p_ca - ram0 * q_am;
  pim0_ = pim_.constant() ? pim_.get(0.0) : (after_steady ? pim_.mean() : pim_.get(0.0));
}

void CoronaryBC::assemble(Assembler& a, double t) const {
  const bool st = a.steady();
  const Node& n = port();
  const int v = internal0_;
  const double ra = ra_.get(t, st), rv = rv_.get(t, st), ca = ca_.get(t, st), cim = cim_.get(t, st);
  const double pim = pim_.get(t, st), pv = pv_.get(t, st);
  const int r0 = row0_, r1 = row0_ + 1;
  if (st) {
    const double ram0 = ram(0.0, true, a.period());
    a.f(r0, v, 1.0);
    a.c(r0, 0.0);
    a.f(r1, n.p, -1.0);
    a.f(r1, n.q, ra + ram0 + rv);
    a.c(r1, pv);
    return;
  }
  const double rm = ram(t, false, a.period());
  a.f(r0, n.q, cim * rv);
  a.f(r0, v, -1.0);
  a.e(r0, n.p, -ca * cim * rv);
  a.e(r0, n.q, ra * ca * cim * rv);
  a.e(r0, v, -cim * rv);
  a.c(r0, cim * (-pim + pv + pim0_ - pcim0_));
  a.f(r1, n.p, cim * rv);
  a.f(r1, n.q, -cim * rv * ra);
  a.f(r1, v, -(rv + rm));
  a.e(r1, v, -cim * rv * rm);
  a.c(r1, rm * cim * pv - cim * (rv + rm) * (pim + pcim0_ - pim0_));
}

}  // namespace flowire::flow::svzerod
