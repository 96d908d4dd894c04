#include "flowire/flow/output.hpp"

#include <fmt/format.h>
#include <fmt/os.h>

#include <cmath>
#include <fstream>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/vessels/io.hpp"

namespace flowire::flow {
namespace {
constexpr double kPi = 3.14159265358979323846;

void check_frame(const Network& net, const FlowFrame& f) {
  const auto ne = static_cast<size_t>(net.num_segments());
  if (f.pressure.size() != static_cast<size_t>(net.num_nodes()) || f.flow.size() != ne ||
      (!f.occupied_fraction.empty() && f.occupied_fraction.size() != ne) ||
      (!f.resistance_factor.empty() && f.resistance_factor.size() != ne))
    throw_usage_error("flow output: a frame's arrays do not match the network");
}
}  // namespace

FlowFrame capture_frame(const FlowSolver& solver) {
  FlowFrame f;
  f.time = solver.time();
  f.pressure.resize(static_cast<size_t>(solver.network().num_nodes()));
  f.flow.resize(static_cast<size_t>(solver.network().num_segments()));
  solver.node_pressures(f.pressure);
  solver.segment_flows(f.flow);
  for (const auto& o : solver.occlusion()) {
    f.occupied_fraction.push_back(o.occupied_fraction);
    f.resistance_factor.push_back(o.resistance_factor);
  }
  return f;
}

std::vector<FlowFrame> sample_frames(FlowSolver& solver, double t0, double duration, int count, bool include_end) {
  if (count < 1) throw_usage_error("sample_frames: count must be at least 1");
  std::vector<FlowFrame> frames;
  frames.reserve(static_cast<size_t>(count));
  const int div = include_end ? std::max(1, count - 1) : count;
  for (int i = 0; i < count; ++i) {
    solver.advance(t0 + duration * i / div);
    frames.push_back(capture_frame(solver));
  }
  return frames;
}

void write_nodes_csv(const Network& net, std::span<const FlowFrame> frames, const std::filesystem::path& path) {
  for (const auto& f : frames) check_frame(net, f);
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "time,node,x,y,z,pressure\n";
    std::string buf;
    for (const auto& f : frames) {
      for (int i = 0; i < net.num_nodes(); ++i) {
        const auto& x = net.node(i);
        buf.clear();
        fmt::format_to(std::back_inserter(buf), "{:.9g},{},{:.9g},{:.9g},{:.9g},{:.12g}\n", f.time, i, x.x(), x.y(),
                       x.z(), f.pressure[static_cast<size_t>(i)]);
        out << buf;
      }
    }
  });
}

void write_segments_csv(const FlowSolver& solver, std::span<const FlowFrame> frames,
                        const std::filesystem::path& path) {
  const auto& net = solver.network();
  const double eta = solver.spec().viscosity, rho = solver.spec().density;
  for (const auto& f : frames) check_frame(net, f);
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "time,segment,node_from,node_to,length,radius,resistance,flow_rate,mean_velocity,wall_shear_stress,reynolds,"
           "occupied_fraction,resistance_factor\n";
    std::string buf;
    for (const auto& f : frames) {
      for (int s = 0; s < net.num_segments(); ++s) {
        const auto& seg = net.segment(s);
        const double q = f.flow[static_cast<size_t>(s)];
        const double r = seg.radius;
        const double v = q / (kPi * r * r);
        buf.clear();
        fmt::format_to(std::back_inserter(buf),
                       "{:.9g},{},{},{},{:.9g},{:.9g},{:.9g},{:.12g},{:.12g},{:.12g},{:.9g},{:.9g},{:.12g}\n", f.time,
                       s, seg.node_from, seg.node_to, seg.length, r, solver.resistance(s), q, v,
                       4.0 * eta * std::abs(q) / (kPi * r * r * r), rho * std::abs(v) * 2.0 * r / eta,
                       f.occupied(static_cast<size_t>(s)), f.factor(static_cast<size_t>(s)));
        out << buf;
      }
    }
  });
}

void write_network_vtp(const FlowSolver& solver, const FlowFrame& frame, const std::filesystem::path& path) {
  const auto& net = solver.network();
  check_frame(net, frame);
  const double eta = solver.spec().viscosity, rho = solver.spec().density;
  const auto ne = static_cast<size_t>(net.num_segments());
  vessels::DataArray q{"flow_rate", frame.flow, 1};
  vessels::DataArray v{"mean_velocity", std::vector<double>(ne), 1};
  vessels::DataArray w{"wall_shear_stress", std::vector<double>(ne), 1};
  vessels::DataArray re{"reynolds", std::vector<double>(ne), 1};
  vessels::DataArray occ{"occupied_fraction", std::vector<double>(ne), 1};
  vessels::DataArray fac{"resistance_factor", std::vector<double>(ne), 1};
  for (size_t s = 0; s < ne; ++s) {
    occ.values[s] = frame.occupied(s);
    fac.values[s] = frame.factor(s);
    const double r = net.segment(static_cast<int>(s)).radius;
    v.values[s] = frame.flow[s] / (kPi * r * r);
    w.values[s] = 4.0 * eta * std::abs(frame.flow[s]) / (kPi * r * r * r);
    re.values[s] = rho * std::abs(v.values[s]) * 2.0 * r / eta;
  }
  vessels::write_network_vtp(net, path.string(), {vessels::DataArray{"pressure", frame.pressure, 1}},
                             {q, v, w, re, occ, fac});
}

void write_network_series(const FlowSolver& solver, std::span<const FlowFrame> frames, const std::filesystem::path& dir,
                          const std::string& stem) {
  if (frames.empty()) throw_usage_error("write_network_series: no frames");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw_input_error(dir.string(), fmt::format("cannot create the output folder: {}", ec.message()));
  std::string pvd =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  "
      "<Collection>\n";
  for (size_t i = 0; i < frames.size(); ++i) {
    const std::string name = fmt::format("{}_{:06d}.vtp", stem, i);
    write_network_vtp(solver, frames[i], dir / name);
    pvd += fmt::format("    <DataSet timestep=\"{:.9g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", frames[i].time, name);
  }
  pvd += "  </Collection>\n</VTKFile>\n";
  write_network_vtp(solver, frames.back(), dir / (stem + ".vtp"));
  write_text_atomically(dir / (stem + ".pvd"), pvd);
}

}  // namespace flowire::flow
