// flowire from Python: networks as numpy arrays, scene runs, a co-simulation stepped from a
// script, the flow at a time. The Python package (flowire/__init__.py) wraps this module.
//
// Arrays are views without copies where the C++ layout allows: a network's nodes (N x 3),
// segments (M x 2, strided over the segment records), radii and lengths, and a flow frame's
// pressures and flows; each view keeps its owner alive through its numpy base and is
// read-only. The wire's arrays are ordered from the base to the tip (as wire.csv), the
// reverse of the rod's storage, so they are fresh arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "flowire/common/config.hpp"
#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/coupling/cosimulation.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/flow/output.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire/vessels/network.hpp"

namespace py = pybind11;
using namespace flowire;

namespace {

/// A read-only array over memory that @p owner keeps alive.
py::array view(py::dtype dtype, std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides, const void* data,
               py::handle owner) {
  py::array a(std::move(dtype), std::move(shape), std::move(strides), data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// The `(N x 3)` array of a vector of 3-vectors (Eigen::Vector3d is three packed doubles).
py::array vec3_view(const std::vector<vessels::Vec3>& v, py::handle owner) {
  static_assert(sizeof(vessels::Vec3) == 3 * sizeof(double));
  return view(py::dtype::of<double>(), {static_cast<py::ssize_t>(v.size()), 3},
              {static_cast<py::ssize_t>(sizeof(vessels::Vec3)), sizeof(double)}, v.data(), owner);
}

py::array doubles_view(const std::vector<double>& v, py::handle owner) {
  return view(py::dtype::of<double>(), {static_cast<py::ssize_t>(v.size())}, {sizeof(double)}, v.data(), owner);
}

/// A fresh (n x 3) array of a list of 3-vectors.
py::array_t<double> vec3_copy(const std::vector<Eigen::Vector3d>& v) {
  py::array_t<double> a({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
  auto m = a.mutable_unchecked<2>();
  for (size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) m(static_cast<py::ssize_t>(i), k) = v[i][k];
  return a;
}

py::array_t<double> vec3_array(const Eigen::Vector3d& v) {
  py::array_t<double> a(3);
  for (int k = 0; k < 3; ++k) a.mutable_at(k) = v[k];
  return a;
}

py::dict counts_dict(const vessels::NetworkCounts& n) {
  py::dict d;
  d["branches"] = n.branches;
  d["nodes"] = n.nodes;
  d["segments"] = n.segments;
  d["junctions"] = n.junctions;
  d["ends"] = n.ends;
  d["loops"] = n.loops;
  d["components"] = n.components;
  d["total_length"] = n.total_length;
  d["radius_min"] = n.radius_min;
  d["radius_max"] = n.radius_max;
  return d;
}

/// A network owned by Python, or one borrowed from a flow / co-simulation that it keeps alive.
/// Marks a binding object as constructed. `Class.__new__(Class)` gives Python an instance whose
/// memory was allocated but never constructed (pybind11 runs no constructor there); the
/// registry of live objects tells such an instance from a real one (live() below).
class Constructed {
 public:
  Constructed() { enter(); }
  Constructed(const Constructed&) { enter(); }
  Constructed& operator=(const Constructed&) { return *this; }
  ~Constructed() {
    const std::lock_guard<std::mutex> lock(mutex());
    registry().erase(this);
  }
  [[nodiscard]] static bool is_live(const Constructed* c) {
    const std::lock_guard<std::mutex> lock(mutex());
    return registry().count(c) > 0;
  }

 private:
  void enter() {
    const std::lock_guard<std::mutex> lock(mutex());
    registry().insert(this);
  }
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static std::unordered_set<const Constructed*>& registry() {
    static std::unordered_set<const Constructed*> r;
    return r;
  }
};

struct PyNetwork {
  std::shared_ptr<const vessels::Network> net;
  py::object keep;  ///< the owner of a borrowed network
  Constructed constructed;
};

/// A flow frame: the state of the network flow at one time.
struct PyFlowFrame {
  flow::FlowFrame frame;
  Constructed constructed;
};

/// The object behind a Python handle. `Class.__new__(Class)` makes an instance that was never
/// constructed: its methods raise flowire.Error instead of reading a null object.
template <class T>
T& live(T* p) {
  // The address of the member is computed, not read: an unconstructed p is never dereferenced.
  if (!p || !Constructed::is_live(&p->constructed))
    throw Error(ErrorKind::Usage, "the object was not constructed: create it with its class, e.g. CoSimulation(scene)");
  return *p;
}

/// Between pieces of long work with the GIL released: Ctrl-C (Python's SIGINT handler) ends
/// the call with KeyboardInterrupt.
void check_python_signals(std::string_view what) {
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) {
    PyErr_Clear();
    throw Error(ErrorKind::Interrupted, fmt::format("{} was interrupted", what));
  }
}

PyFlowFrame frame_at(flow::FlowSolver& fs, const vessels::Network& net, double t) {
  if (!std::isfinite(t)) throw_usage_error(fmt::format("Flow.at: t = {} is not a finite time", t));
  if (fs.spec().model == flow::Model::Rlc) {
    if (t < fs.time())
      throw_usage_error("the rlc flow model integrates forward in time only: ask for t >= the current time");
    // The rlc model steps there: in pieces of 0.1 s of flow, with Ctrl-C heard between them.
    while (fs.time() < t - 0.1) {
      fs.advance(fs.time() + 0.1);
      check_python_signals("Flow.at");
    }
  }
  PyFlowFrame f;
  f.frame.time = t;
  f.frame.pressure.resize(static_cast<size_t>(net.num_nodes()));
  f.frame.flow.resize(static_cast<size_t>(net.num_segments()));
  fs.solve_at(t, f.frame.pressure, f.frame.flow);
  return f;
}

std::vector<std::string> overrides(const std::optional<std::vector<std::string>>& set) {
  return set ? *set : std::vector<std::string>{};
}

/// A scene file as the command line loads it (same checks, same messages).
config::Config load(const std::string& scene, const std::vector<std::string>& sets, const std::string& out) {
  check_input_file(scene, input_limit::kScene, "a scene (YAML)");
  if (std::filesystem::path(scene).extension() == ".json")
    throw Error(ErrorKind::Usage, scene + ": svZeroDSolver models run with the command line (flowire run MODEL.json)");
  return coupling::load_scene(scene, sets, out);
}

/// The flow of a scene's network alone (its vessels: and flow: sections).
struct PyFlow {
  explicit PyFlow(const std::string& scene, const std::vector<std::string>& sets) : config(load(scene, sets, {})) {
    if (!config.has_section("flow")) throw_input_error(config.where("flow"), "the scene has no flow: section");
    net = std::make_shared<vessels::Network>(coupling::build_scene_network(config));
    solver = flow::make_solver(*net, flow::from_config(config, *net));
  }
  config::Config config;
  std::shared_ptr<const vessels::Network> net;
  std::unique_ptr<flow::FlowSolver> solver;
  Constructed constructed;
};

/// A co-simulation stepped from Python.
struct PyCoSimulation {
  PyCoSimulation(const std::string& scene, const std::vector<std::string>& sets)
      : config(load(scene, sets, {})), sim(std::make_unique<coupling::CoSimulation>(config)) {
    sim->start();
  }
  config::Config config;
  std::unique_ptr<coupling::CoSimulation> sim;
  Constructed constructed;
  [[nodiscard]] rod::RodSimulator& rod() const {
    if (!sim->rod()) throw_usage_error("the scene has no wire: section");
    return *sim->rod();
  }
};

}  // namespace

PYBIND11_MODULE(_flowire, m) {
  m.doc() = "flowire: guidewire and blood-flow co-simulation in vessel networks";

  // flowire::Error → flowire.Error (InputError, NumericalError); the message is the one the
  // command line prints after "flowire: error: " (file and place first).
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<Error> input_error(m, "InputError", error.ptr());
  static py::exception<Error> numerical_error(m, "NumericalError", error.ptr());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      if (e.kind() == ErrorKind::Interrupted)
        PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
      else if (e.kind() == ErrorKind::Numerical)
        numerical_error(e.what());
      else
        input_error(e.what());
    }
  });

  m.def("take_warnings", &take_warnings, "Warnings collected since the last call (and cleared).");

  py::class_<PyNetwork>(m, "Network", "A vessel network: nodes joined by cylindrical (or tapered) segments.")
      .def_property_readonly(
          "nodes", [](py::object self) { return vec3_view(live(self.cast<PyNetwork*>()).net->nodes(), self); },
          "(N x 3) node positions [m], a read-only view")
      .def_property_readonly(
          "segments",
          [](py::object self) {
            const auto& s = live(self.cast<PyNetwork*>()).net->segments();
            static_assert(offsetof(vessels::Segment, node_to) == offsetof(vessels::Segment, node_from) + sizeof(int));
            return view(py::dtype::of<int>(), {static_cast<py::ssize_t>(s.size()), 2},
                        {static_cast<py::ssize_t>(sizeof(vessels::Segment)), sizeof(int)},
                        s.empty() ? nullptr : &s.front().node_from, self);
          },
          "(M x 2) node ids of each segment (from, to), a read-only view over the segment records")
      .def_property_readonly(
          "radius",
          [](py::object self) {
            const auto& s = live(self.cast<PyNetwork*>()).net->segments();
            return view(py::dtype::of<double>(), {static_cast<py::ssize_t>(s.size())},
                        {static_cast<py::ssize_t>(sizeof(vessels::Segment))}, s.empty() ? nullptr : &s.front().radius,
                        self);
          },
          "(M) mean radius of each segment [m], a read-only view")
      .def_property_readonly(
          "length",
          [](py::object self) {
            const auto& s = live(self.cast<PyNetwork*>()).net->segments();
            return view(py::dtype::of<double>(), {static_cast<py::ssize_t>(s.size())},
                        {static_cast<py::ssize_t>(sizeof(vessels::Segment))}, s.empty() ? nullptr : &s.front().length,
                        self);
          },
          "(M) length of each segment [m], a read-only view")
      .def_property_readonly("branch_names",
                             [](const PyNetwork* n_ptr) {
                               auto& n = live(n_ptr);
                               std::vector<std::string> names;
                               for (const auto& b : n.net->branches()) names.push_back(b.name);
                               return names;
                             })
      .def(
          "counts",
          [](const PyNetwork* n_ptr) {
            auto& n = live(n_ptr);
            return counts_dict(n.net->counts());
          },
          "branches, nodes, segments, junctions, ends, loops, components, total_length, radius_min, radius_max "
          "(as `flowire network info --json`)")
      .def(
          "widest_end",
          [](const PyNetwork* n_ptr) {
            auto& n = live(n_ptr);
            return n.net->widest_end();
          },
          "the default flow inlet node")
      .def("__repr__", [](const PyNetwork* n_ptr) {
        auto& n = live(n_ptr);
        const auto c = n.net->counts();
        return "<flowire.Network: " + std::to_string(c.nodes) + " nodes, " + std::to_string(c.segments) + " segments>";
      });

  m.def(
      "read_network",
      [](const std::string& path, const std::optional<std::string>& length_unit, double max_segment_length) {
        vessels::ReadOptions ro;
        if (length_unit) ro.length_unit = *length_unit;
        if (max_segment_length > 0) ro.build.max_segment_length = max_segment_length;
        py::gil_scoped_release nogil;
        return PyNetwork{std::make_shared<vessels::Network>(vessels::read_network(path, ro)), {}, {}};
      },
      py::arg("path"), py::arg("length_unit") = py::none(), py::arg("max_segment_length") = 0.0,
      "Read a vessel network file (.vtp, .vtk, .yaml, svZeroDSolver .json, svOneDSolver .in).");

  py::class_<PyFlowFrame>(m, "FlowFrame", "The network flow at one time.")
      .def_property_readonly("time",
                             [](const PyFlowFrame* f_ptr) {
                               auto& f = live(f_ptr);
                               return f.frame.time;
                             })
      .def_property_readonly(
          "pressure",
          [](py::object self) { return doubles_view(live(self.cast<PyFlowFrame*>()).frame.pressure, self); },
          "(N) pressure at each node [Pa], a read-only view")
      .def_property_readonly(
          "flow", [](py::object self) { return doubles_view(live(self.cast<PyFlowFrame*>()).frame.flow, self); },
          "(M) volume flow through each segment, from its node_from to its node_to [m^3/s], a read-only view");

  py::class_<PyFlow>(m, "Flow", "The network flow of a scene (its vessels: and flow: sections).")
      .def(py::init([](const std::string& scene, const std::optional<std::vector<std::string>>& set) {
             return std::make_unique<PyFlow>(scene, overrides(set));
           }),
           py::arg("scene"), py::arg("set") = py::none())
      .def_property_readonly("network",
                             [](py::object self) {
                               return PyNetwork{live(self.cast<PyFlow*>()).net, self, {}};
                             })
      .def_property_readonly("solver",
                             [](const PyFlow* f_ptr) {
                               auto& f = live(f_ptr);
                               return std::string(f.solver->name());
                             })
      .def_property_readonly("time",
                             [](const PyFlow* f_ptr) {
                               auto& f = live(f_ptr);
                               return f.solver->time();
                             })
      .def(
          "at",
          [](PyFlow* f_ptr, double t) {
            auto& f = live(f_ptr);
            py::gil_scoped_release nogil;
            return frame_at(*f.solver, *f.net, t);
          },
          py::arg("t"), "The pressures and flows at time t [s] (the rlc model: t not before the last time asked).");

  py::class_<PyCoSimulation>(m, "CoSimulation",
                             "A scene's co-simulation stepped from Python: set the insertion between steps, read the "
                             "wire, its forces and the clamp force. Writes no files.")
      .def(py::init([](const std::string& scene, const std::optional<std::vector<std::string>>& set) {
             py::gil_scoped_release nogil;
             return std::make_unique<PyCoSimulation>(scene, overrides(set));
           }),
           py::arg("scene"), py::arg("set") = py::none())
      .def(
          "step",
          [](PyCoSimulation* s_ptr, long n) {
            auto& s = live(s_ptr);
            py::gil_scoped_release nogil;
            for (long i = 0; i < n; ++i) {
              s.sim->step();
              check_python_signals("CoSimulation.step");
            }
          },
          py::arg("n") = 1, "Advance n steps of solve.dt.")
      .def_property_readonly("dt",
                             [](const PyCoSimulation* s_ptr) {
                               auto& s = live(s_ptr);
                               return s.sim->dt();
                             })
      .def_property_readonly("time",
                             [](const PyCoSimulation* s_ptr) {
                               auto& s = live(s_ptr);
                               return s.sim->time();
                             })
      .def_property_readonly("step_count",
                             [](const PyCoSimulation* s_ptr) {
                               auto& s = live(s_ptr);
                               return s.sim->step_count();
                             })
      .def_property_readonly(
          "planned_steps",
          [](const PyCoSimulation* s_ptr) {
            auto& s = live(s_ptr);
            return s.sim->planned_steps();
          },
          "steps of solve.duration")
      .def_property_readonly("unconverged_steps",
                             [](const PyCoSimulation* s_ptr) {
                               auto& s = live(s_ptr);
                               return s.sim->unconverged_steps();
                             })
      .def_property(
          "insertion_speed",
          [](const PyCoSimulation* s_ptr) {
            auto& s = live(s_ptr);
            (void)s.rod();
            return s.sim->insertion_speed();
          },
          [](PyCoSimulation* s_ptr, double v) {
            auto& s = live(s_ptr);
            s.sim->set_insertion_speed(v);
          },
          "feeding speed at the clamp [m/s] for the next steps (> 0 pushes in)")
      .def_property(
          "rotation_speed",
          [](const PyCoSimulation* s_ptr) {
            auto& s = live(s_ptr);
            (void)s.rod();
            return s.sim->rotation_speed();
          },
          [](PyCoSimulation* s_ptr, double w) {
            auto& s = live(s_ptr);
            s.sim->set_rotation_speed(w);
          },
          "clamp rotation speed about the insertion direction [rad/s]")
      .def_property_readonly("inserted_length",
                             [](const PyCoSimulation* s_ptr) {
                               auto& s = live(s_ptr);
                               return s.rod().inserted_length();
                             })
      .def_property_readonly("tip",
                             [](const PyCoSimulation* s_ptr) {
                               auto& s = live(s_ptr);
                               return vec3_array(s.rod().tip_position());
                             })
      .def_property_readonly(
          "base_force",
          [](const PyCoSimulation* s_ptr) {
            auto& s = live(s_ptr);
            return vec3_array(s.rod().base_force());
          },
          "force the clamp exerts on the wire in the last step [N]")
      .def_property_readonly(
          "base_torque",
          [](const PyCoSimulation* s_ptr) {
            auto& s = live(s_ptr);
            return vec3_array(s.rod().base_torque());
          },
          "torque the clamp exerts on the wire about the entry point [N m]")
      .def(
          "wire",
          [](const PyCoSimulation* s_ptr) {
            auto& s = live(s_ptr);
            (void)s.rod();
            const coupling::WireFrame f = s.sim->wire_frame();
            py::dict d;
            d["time"] = f.time;
            d["s"] = py::array_t<double>(static_cast<py::ssize_t>(f.s.size()), f.s.data());
            d["x"] = vec3_copy(f.x);
            d["force"] = vec3_copy(f.force);
            const std::vector<Eigen::Vector3d> zero(f.x.size(), Eigen::Vector3d::Zero());
            d["drag"] = vec3_copy(f.drag.empty() ? zero : f.drag);
            d["contact"] = vec3_copy(f.contact.empty() ? zero : f.contact);
            d["flow_velocity"] = vec3_copy(f.flow_velocity);
            return d;
          },
          "The inserted wire from the base (s = 0) to the tip: s (n), x (n x 3) [m], force, drag, contact "
          "(n x 3) [N], flow_velocity (n x 3) [m/s] (as wire.csv)")
      .def_property_readonly(
          "vertices",
          [](const PyCoSimulation* s_ptr) {
            auto& s = live(s_ptr);
            return vec3_copy(s.sim->wire_frame().x);
          },
          "(n x 3) inserted wire vertices from the base to the tip [m]")
      .def_property_readonly("network",
                             [](py::object self) -> py::object {
                               auto& s = live(self.cast<PyCoSimulation*>());
                               if (!s.sim->network()) return py::none();
                               // Borrowed: the co-simulation object owns it and is kept alive.
                               std::shared_ptr<const vessels::Network> net(s.sim->network(),
                                                                           [](const vessels::Network*) {});
                               return py::cast(PyNetwork{net, self, {}});
                             })
      .def(
          "flow",
          [](const PyCoSimulation* s_ptr) -> py::object {
            auto& s = live(s_ptr);
            if (!s.sim->flow()) return py::none();
            PyFlowFrame f;
            f.frame = flow::capture_frame(*s.sim->flow());
            return py::cast(std::move(f));
          },
          "The network flow at the last flow update (None without a flow: section).");

  m.def(
      "_run",
      [](const std::string& scene, const std::string& out, const std::vector<std::string>& sets) {
        const auto cfg = load(scene, sets, out);
        std::string summary;
        {
          py::gil_scoped_release nogil;
          coupling::RunOptions options;  // Ctrl-C between steps ends the run, its summary "interrupted"
          options.progress = [](const coupling::Progress&) { check_python_signals("the run"); };
          summary = coupling::run_scene(cfg, options).summary.dump();
        }
        return summary;
      },
      py::arg("scene"), py::arg("out"), py::arg("set"));
}
