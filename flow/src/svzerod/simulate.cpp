// The svZeroDSolver run: steady initial phase, pulsatile cycles, output as the peer writes it.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/svzerod/integrator.hpp"
#include "flowire/flow/svzerod/model.hpp"
#include "flowire/flow/svzerod/simulate.hpp"

namespace flowire::flow::svzerod {
namespace {

/// The output states: their sums (mean only), or every one of them.
class Recorder {
 public:
  Recorder(int n, bool mean_only) : mean_only_(mean_only) {
    if (mean_only_) {
      sum_y_ = Eigen::VectorXd::Zero(n);
      sum_yd_ = Eigen::VectorXd::Zero(n);
    }
  }
  void record(double time, const State& s) {
    ++count_;
    if (mean_only_) {
      sum_y_ += s.y;
      sum_yd_ += s.yd;
      return;
    }
    times_.push_back(time);
    states_.push_back(s);
  }
  [[nodiscard]] long count() const { return count_; }
  [[nodiscard]] Eigen::VectorXd mean_y() const { return sum_y_ / static_cast<double>(count_); }
  [[nodiscard]] Eigen::VectorXd mean_yd() const { return sum_yd_ / static_cast<double>(count_); }
  std::vector<double>& times() { return times_; }
  [[nodiscard]] const std::vector<State>& states() const { return states_; }

 private:
  bool mean_only_;
  long count_ = 0;
  Eigen::VectorXd sum_y_, sum_yd_;
  std::vector<double> times_;
  std::vector<State> states_;
};

Result make_result(const Model& m, Recorder& rec) {
  const auto& sp = m.sim;
  Result r;
  r.variable_based = sp.variable_based;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd my, myd;
  if (sp.mean_only) {
    my = rec.mean_y();
    myd = rec.mean_yd();
  }
  if (sp.variable_based) {
    r.columns = {"name", "time", "y"};
    if (sp.derivative) r.columns.emplace_back("ydot");
    for (size_t d = 0; d < m.dofs.size(); ++d) {
      const auto& name = m.dofs[d];
      const int i = m.dof_unknown[d];
      if (sp.mean_only) {
        r.names.push_back(name);
        r.times.push_back(nan);
        std::vector<double> row = {my[i]};
        if (sp.derivative) row.push_back(myd[i]);
        r.data.push_back(row);
        continue;
      }
      for (size_t k = 0; k < rec.states().size(); ++k) {
        r.names.push_back(name);
        r.times.push_back(rec.times()[k]);
        std::vector<double> row = {rec.states()[k].y[i]};
        if (sp.derivative) row.push_back(rec.states()[k].yd[i]);
        r.data.push_back(row);
      }
    }
    return r;
  }
  r.columns = {"name", "time", "flow_in", "flow_out", "pressure_in", "pressure_out"};
  if (sp.derivative)
    for (const char* c : {"d_flow_in", "d_flow_out", "d_pressure_in", "d_pressure_out"}) r.columns.emplace_back(c);
  for (const auto& v : m.vessels) {
    const Node& a = v.block->inlets()[0];
    const Node& o = v.block->outlets()[0];
    auto row_of = [&](const Eigen::VectorXd& y, const Eigen::VectorXd& yd) {
      std::vector<double> row = {y[a.q], y[o.q], y[a.p], y[o.p]};
      if (sp.derivative) row.insert(row.end(), {yd[a.q], yd[o.q], yd[a.p], yd[o.p]});
      return row;
    };
    if (sp.mean_only) {
      r.names.push_back(v.block->name());
      r.times.push_back(nan);
      r.data.push_back(row_of(my, myd));
      continue;
    }
    for (size_t k = 0; k < rec.states().size(); ++k) {
      r.names.push_back(v.block->name());
      r.times.push_back(rec.times()[k]);
      r.data.push_back(row_of(rec.states()[k].y, rec.states()[k].yd));
    }
  }
  return r;
}

}  // namespace

namespace {
Result simulate_model(Model& m, const std::string& json_path, const Stopwatch& sw, Summary* summary) {
  auto& sp = m.sim;
  if (sp.cycle_error && m.has_rcr) {
    // Enough cycles for the slowest RCR to settle within the error: checked before it is an int.
    const double cycles = std::max(1.0, std::ceil(-m.max_tau / m.period * std::log(sp.cycle_error_value)));
    check_time_steps(m.file, sp.pts, cycles,
                     "the cycles sim_cycle_to_cycle_percent_error asks for (RCR time constant / period)");
    sp.cycles = static_cast<int>(cycles);
  }
  const int num_steps = (sp.pts - 1) * sp.cycles + 1;
  const double dt = m.period / (static_cast<double>(sp.pts) - 1.0);

  System sys(m.block_pointers(), m.unknowns, m.period, m.file);
  State state = m.initial;
  long factorizations = 0;
  if (sp.steady_initial) {
    // Steady: tables at their mean, RCR capacitors removed; 31 steps of a tenth of the period.
    sys.set_phase(true, 0.0);
    GeneralizedAlpha steady(sys, sp.rho, m.period / 10.0, sp.atol, sp.max_iter, m.file);
    for (int i = 0; i < 31; ++i) steady.step(state, m.period / 10.0 * i);
  }
  for (auto& b : m.blocks) b->prepare(state.y, state.yd, sp.steady_initial, m.period);
  sys.set_phase(false, 0.0);
  GeneralizedAlpha integ(sys, sp.rho, dt, sp.atol, sp.max_iter, m.file);

  Recorder rec(m.unknowns, sp.mean_only);
  const int start_last = num_steps - 1 - (sp.pts - 1) * sp.last_cycles;
  double time = 0.0;
  if (sp.all_cycles || 0 >= start_last) rec.record(time, state);
  int counter = 0;
  std::vector<State> last_states;  // the states of the last two cycles (cycle-to-cycle error)
  const int keep_from = num_steps - (2 * (sp.pts - 1) + 1);
  const bool track = sp.cycle_error && !m.has_rcr;
  if (track && keep_from <= 0) last_states.push_back(state);
  for (int i = 1; i < num_steps; ++i) {
    if (track && i == keep_from + 1 && keep_from > 0) last_states.push_back(state);
    integ.step(state, time);
    if (track && i > keep_from) last_states.push_back(state);
    ++counter;
    time = dt * i;
    if (counter == sp.output_interval || (!sp.all_cycles && i == start_last)) {
      if (sp.all_cycles || i >= start_last) rec.record(time, state);
      counter = 0;
    }
  }
  int cycles = sp.cycles;
  if (track) {
    // Extra cycles until the mean flow and pressure at the vessel caps (inlet node of
    // inlet vessels, outlet node of outlet vessels) change by less than the tolerance.
    std::vector<std::pair<int, int>> caps;
    for (const auto& v : m.vessels) {
      if (v.cap == 1 || v.cap == 3)
        caps.emplace_back(v.block->inlets()[0].q, v.block->inlets()[0].p);
      else if (v.cap == 2)
        caps.emplace_back(v.block->outlets()[0].q, v.block->outlets()[0].p);
    }
    const auto two = static_cast<size_t>(2 * (sp.pts - 1) + 1);
    auto converged = [&]() {
      if (last_states.size() < two) return true;
      const size_t base = last_states.size() - two;
      for (const auto& [qd, pd] : caps) {
        double q0 = 0, p0 = 0, q1 = 0, p1 = 0;
        for (int i = 0; i < sp.pts; ++i) {
          q0 += last_states[base + static_cast<size_t>(i)].y[qd];
          p0 += last_states[base + static_cast<size_t>(i)].y[pd];
          q1 += last_states[base + static_cast<size_t>(sp.pts - 1 + i)].y[qd];
          p1 += last_states[base + static_cast<size_t>(sp.pts - 1 + i)].y[pd];
        }
        if (std::abs((q1 - q0) / q0) > sp.cycle_error_value || std::abs((p1 - p0) / p0) > sp.cycle_error_value)
          return false;
      }
      return true;
    };
    for (int extra = 0; extra < 10000 && !converged(); ++extra) {
      ++cycles;
      for (int i = 1; i < sp.pts; ++i) {
        integ.step(state, time);
        last_states.push_back(state);
        ++counter;
        time = dt * i;
        if (counter == sp.output_interval || (!sp.all_cycles && i == start_last)) {
          if (sp.all_cycles || i >= start_last) rec.record(time, state);
          counter = 0;
        }
      }
    }
  }
  if (!sp.all_cycles && !rec.times().empty()) {
    const double t0 = rec.times()[0];
    for (auto& t : rec.times()) t -= t0;
  }
  factorizations = sys.factorizations();
  Result r = make_result(m, rec);
  if (summary) {
    summary->model = json_path;
    summary->vessels = static_cast<int>(m.vessels.size());
    summary->junctions = m.junctions;
    summary->boundary_conditions = m.boundary_conditions;
    summary->unknowns = m.unknowns;
    summary->cycles = cycles;
    summary->steps = num_steps - 1;
    summary->rows = static_cast<int>(r.names.size());
    summary->period = m.period;
    summary->dt = dt;
    summary->newton_iterations_per_step = integ.solves_per_step();
    summary->factorizations = factorizations;
    summary->seconds = sw.seconds();
  }
  return r;
}
}  // namespace

Result simulate(const std::string& json_path, Summary* summary, const Options& options) {
  Stopwatch sw;
  Model m = read_model(json_path, options);
  return simulate_model(m, json_path, sw, summary);
}

Result simulate(const nlohmann::json& model, const std::string& name, Summary* summary, const Options& options) {
  Stopwatch sw;
  Model m = read_model(model, name, options);
  return simulate_model(m, name, sw, summary);
}

void write_result_csv(const Result& r, const std::filesystem::path& path) {
  std::string out;
  out.reserve(r.names.size() * 128 + 64);
  for (size_t c = 0; c < r.columns.size(); ++c) out += (c ? "," : "") + r.columns[c];
  out += "\n";
  for (size_t i = 0; i < r.names.size(); ++i) {
    out += r.names[i];
    out += ',';
    if (!std::isnan(r.times[i])) out += fmt::format("{:.16e}", r.times[i]);
    for (double x : r.data[i]) {
      out += ',';
      out += fmt::format("{:.16e}", x);
    }
    out += '\n';
  }
  write_text_atomically(path, out);
}

Summary run(const std::string& json_path, const std::filesystem::path& out_dir) {
  Summary s;
  const Result r = simulate(json_path, &s);
  std::filesystem::create_directories(out_dir);
  s.result_file = (out_dir / "svzerod_result.csv").string();
  write_result_csv(r, s.result_file);
  return s;
}

}  // namespace flowire::flow::svzerod
