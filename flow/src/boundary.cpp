// The outlet catalogue (spec.hpp OutletBC): steady laws, impedances, svZeroDSolver form.
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "flowire/common/error.hpp"
#include "flowire/flow/spec.hpp"

namespace flowire::flow {

namespace {

using nlohmann::json;
using Type = OutletBC::Type;

constexpr int kSineSamples = 128;  // a sine written as a table: samples per period

/// A waveform as svZeroDSolver writes a parameter: a number, or values over the list `t`.
void put_waveform(json& values, const char* key, const Waveform& w) {
  if (w.is_constant()) {
    values[key] = w.value;
    return;
  }
  std::vector<double> t, v;
  if (w.kind == Waveform::Kind::Table) {
    t = w.times;
    v = w.values;
  } else {  // sine: one period, both ends
    for (int k = 0; k <= kSineSamples; ++k) {
      t.push_back(w.period * k / kSineSamples);
      v.push_back(w(t.back()));
    }
  }
  values["t"] = t;
  values[key] = v;
}

/// A parameter of an svZeroDSolver boundary condition as a waveform (number or list over `t`).
Waveform get_waveform(const json& values, const char* key, const std::string& where) {
  const json& x = values.at(key);
  if (x.is_number()) return Waveform::constant(x.get<double>());
  if (!x.is_array() || x.empty() || !values.contains("t") || !values.at("t").is_array())
    throw_input_error(where, fmt::format("'{}' must be a number, or a list beside a time list 't'", key));
  std::vector<double> t, v;
  try {
    t = values.at("t").get<std::vector<double>>();
    v = x.get<std::vector<double>>();
  } catch (const json::exception&) {
    throw_input_error(where, fmt::format("'{}' and 't' must be lists of numbers", key));
  }
  if (v.size() == 1) return Waveform::constant(v[0]);
  if (t.size() != v.size())
    throw_input_error(where, fmt::format("'{}' has {} values but 't' has {}", key, v.size(), t.size()));
  for (size_t i = 1; i < t.size(); ++i)
    if (!(t[i] > t[i - 1])) throw_input_error(where, "the times 't' must increase");
  return Waveform::table(std::move(t), std::move(v));
}

double get_number(const json& values, const char* key, const std::string& where, bool required = true,
                  double fallback = 0.0) {
  if (!values.contains(key)) {
    if (required) throw_input_error(where, fmt::format("the value '{}' is missing", key));
    return fallback;
  }
  const json& x = values.at(key);
  if (x.is_number()) return x.get<double>();
  if (x.is_array() && x.size() == 1 && x[0].is_number()) return x[0].get<double>();
  throw_input_error(where, fmt::format("'{}' must be a number (a table over time is not taken here)", key));
}

void require(bool ok, const std::string& where, const std::string& what) {
  if (!ok) throw_input_error(where, what);
}

bool finite_nonnegative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

OutletBC OutletBC::at_pressure(double p) {
  OutletBC o;
  o.type = Type::Pressure;
  o.pressure = Waveform::constant(p);
  return o;
}

OutletBC OutletBC::with_resistance(double r, double pd) {
  OutletBC o;
  o.type = Type::Resistance;
  o.resistance = r;
  o.distal_pressure = pd;
  return o;
}

OutletBC OutletBC::rcr(double rp, double c, double rd, double pd) {
  OutletBC o;
  o.type = Type::Rcr;
  o.rp = rp;
  o.c = c;
  o.rd = rd;
  o.distal_pressure = pd;
  return o;
}

std::string_view OutletBC::kind() const {
  switch (type) {
    case Type::Pressure:
      return "PRESSURE";
    case Type::Resistance:
      return "RESISTANCE";
    case Type::Rcr:
      return "RCR";
    case Type::Coronary:
      return "CORONARY";
    case Type::Flow:
      return "FLOW";
  }
  return "?";
}

bool OutletBC::dynamic() const { return (type == Type::Rcr && c > 0.0) || type == Type::Coronary; }

double OutletBC::steady_resistance() const {
  switch (type) {
    case Type::Resistance:
      return resistance;
    case Type::Rcr:
      return rp + rd;
    case Type::Coronary:
      return coronary.ra + coronary.ram + coronary.rv;
    case Type::Pressure:
    case Type::Flow:
      return 0.0;
  }
  return 0.0;
}

double OutletBC::steady_pressure() const {
  switch (type) {
    case Type::Resistance:
    case Type::Rcr:
      return distal_pressure;
    case Type::Coronary:
      return coronary.pv;
    case Type::Pressure:
      return pressure.mean();
    case Type::Flow:
      return 0.0;
  }
  return 0.0;
}

std::complex<double> OutletBC::impedance(double omega) const {
  using C = std::complex<double>;
  const C iw(0.0, omega);
  switch (type) {
    case Type::Resistance:
      return resistance;
    case Type::Rcr:
      return rp + rd / (1.0 + iw * rd * c);
    case Type::Coronary: {
      const auto& k = coronary;
      const C distal = k.ram + 1.0 / (iw * k.cim + 1.0 / k.rv);  // Ram, then Cim ∥ Rv
      return k.ra + 1.0 / (iw * k.ca + 1.0 / distal);            // Ra, then Ca ∥ the rest
    }
    case Type::Pressure:
    case Type::Flow:
      break;
  }
  throw_usage_error(fmt::format("flow: a {} outlet has no impedance", kind()));
}

json OutletBC::to_svzerod(const std::string& name) const {
  json values = json::object();
  switch (type) {
    case Type::Pressure:
      put_waveform(values, "P", pressure);
      break;
    case Type::Flow:
      put_waveform(values, "Q", flow);
      break;
    case Type::Resistance:
      values = {{"R", resistance}, {"Pd", distal_pressure}};
      break;
    case Type::Rcr:
      values = {{"Rp", rp}, {"C", c}, {"Rd", rd}, {"Pd", distal_pressure}};
      break;
    case Type::Coronary:
      values = {{"Ra1", coronary.ra}, {"Ra2", coronary.ram}, {"Rv1", coronary.rv},
                {"Ca", coronary.ca},  {"Cc", coronary.cim},  {"P_v", coronary.pv}};
      put_waveform(values, "Pim", coronary.pim);
      break;
  }
  return {{"bc_name", name}, {"bc_type", std::string(kind())}, {"bc_values", values}};
}

OutletBC OutletBC::from_svzerod(const json& bc, const std::string& where) {
  if (!bc.is_object() || !bc.contains("bc_type") || !bc.at("bc_type").is_string())
    throw_input_error(where, "a boundary condition needs its bc_type");
  const std::string type = bc.at("bc_type").get<std::string>();
  const std::string at = bc.contains("bc_name") && bc.at("bc_name").is_string()
                             ? fmt::format("{}: '{}'", where, bc.at("bc_name").get<std::string>())
                             : where;
  if (!bc.contains("bc_values") || !bc.at("bc_values").is_object())
    throw_input_error(at, "a boundary condition needs its bc_values");
  const json& v = bc.at("bc_values");
  OutletBC o;
  try {
    if (type == "PRESSURE") {
      o.type = Type::Pressure;
      o.pressure = get_waveform(v, "P", at);
    } else if (type == "FLOW") {
      o.type = Type::Flow;
      o.flow = get_waveform(v, "Q", at);
    } else if (type == "RESISTANCE") {
      o = with_resistance(get_number(v, "R", at), get_number(v, "Pd", at, false));
    } else if (type == "RCR") {
      o = rcr(get_number(v, "Rp", at), get_number(v, "C", at), get_number(v, "Rd", at), get_number(v, "Pd", at, false));
    } else if (type == "CORONARY") {
      o.type = Type::Coronary;
      o.coronary.ra = get_number(v, "Ra1", at);
      o.coronary.ram = get_number(v, "Ra2", at);
      o.coronary.rv = get_number(v, "Rv1", at);
      o.coronary.ca = get_number(v, "Ca", at);
      o.coronary.cim = get_number(v, "Cc", at);
      o.coronary.pv = get_number(v, "P_v", at);
      o.coronary.pim = get_waveform(v, "Pim", at);
    } else {
      throw_input_error(at, fmt::format("bc_type '{}' is not an outlet condition flowire takes (PRESSURE, FLOW, "
                                        "RESISTANCE, RCR, CORONARY)",
                                        type));
    }
  } catch (const json::exception& e) {
    throw_input_error(at, e.what());
  }
  o.check(at);
  return o;
}

void OutletBC::check(const std::string& where) const {
  auto nonneg = [&](double x, const char* what) {
    require(finite_nonnegative(x), where, fmt::format("{} = {} must be a finite value >= 0", what, x));
  };
  auto finite = [&](double x, const char* what) {
    require(std::isfinite(x), where, fmt::format("{} = {} is not finite", what, x));
  };
  switch (type) {
    case Type::Pressure:
      finite(pressure.mean(), "the pressure");
      break;
    case Type::Flow:
      finite(flow.mean(), "the flow");
      break;
    case Type::Resistance:
      require(std::isfinite(resistance) && resistance > 0.0, where,
              fmt::format("the resistance {} must be positive", resistance));
      finite(distal_pressure, "the distal pressure Pd");
      break;
    case Type::Rcr:
      nonneg(rp, "Rp");
      nonneg(c, "C");
      nonneg(rd, "Rd");
      require(rp + rd > 0.0, where, "Rp + Rd must be positive");
      finite(distal_pressure, "Pd");
      break;
    case Type::Coronary:
      nonneg(coronary.ra, "Ra");
      nonneg(coronary.ram, "Ram");
      nonneg(coronary.rv, "Rv");
      nonneg(coronary.ca, "Ca");
      nonneg(coronary.cim, "Cim");
      require(coronary.rv > 0.0, where, "a coronary bed needs Rv > 0 (its path to the venous pressure)");
      finite(coronary.pv, "Pv");
      finite(coronary.pim.mean(), "Pim");
      break;
  }
}

}  // namespace flowire::flow
