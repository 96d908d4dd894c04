#include "flowire/coupling/wire_output.hpp"

#include <fmt/format.h>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"

#ifdef FLOWIRE_HAVE_VTK
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyLine.h>
#include <vtkXMLPolyDataWriter.h>
#endif

namespace flowire::coupling {

WireOutput::WireOutput(std::filesystem::path dir, bool csv, bool vtk, std::string name)
    : dir_(std::move(dir)), csv_(csv), vtk_(vtk), name_(std::move(name)) {
  if (csv_) {
    wire_csv_ = "time,vertex,s,x,y,z,drag_x,drag_y,drag_z,contact_x,contact_y,contact_z\n";
    tip_csv_ = "time,inserted_length,x,y,z\n";
    base_csv_ = "time,fx,fy,fz,tx,ty,tz\n";
  }
}

void WireOutput::add_base(double time, const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  if (!csv_) return;
  base_csv_ += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", time, force.x(), force.y(), force.z(),
                           torque.x(), torque.y(), torque.z());
}

void WireOutput::add_tip(double time, double inserted_length, const Eigen::Vector3d& tip) {
  if (!csv_) return;
  tip_csv_ += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", time, inserted_length, tip.x(), tip.y(), tip.z());
}

void WireOutput::add_frame(const WireFrame& f) {
  ++frame_count_;
  auto at = [](const std::vector<Eigen::Vector3d>& v, size_t i) {
    return i < v.size() ? v[i] : Eigen::Vector3d::Zero();
  };
  if (csv_)
    for (size_t i = 0; i < f.x.size(); ++i) {
      const Eigen::Vector3d d = at(f.drag, i), c = at(f.contact, i);
      wire_csv_ +=
          fmt::format("{:.9g},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n", f.time, i,
                      f.s[i], f.x[i].x(), f.x[i].y(), f.x[i].z(), d.x(), d.y(), d.z(), c.x(), c.y(), c.z());
    }
#ifdef FLOWIRE_HAVE_VTK
  if (!vtk_) return;
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  const auto n = static_cast<vtkIdType>(f.x.size());
  pts->SetNumberOfPoints(n);
  vtkNew<vtkPolyLine> line;
  line->GetPointIds()->SetNumberOfIds(n);
  for (vtkIdType i = 0; i < n; ++i) {
    const auto& p = f.x[static_cast<size_t>(i)];
    pts->SetPoint(i, p.x(), p.y(), p.z());
    line->GetPointIds()->SetId(i, i);
  }
  vtkNew<vtkCellArray> cells;
  cells->InsertNextCell(line);
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(pts);
  poly->SetLines(cells);
  auto add = [&](const char* name, int comps, auto&& value) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name);
    a->SetNumberOfComponents(comps);
    a->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i) value(static_cast<size_t>(i), a->GetPointer(i * comps));
    poly->GetPointData()->AddArray(a);
  };
  add("s", 1, [&](size_t i, double* out) { out[0] = f.s[i]; });
  auto vec = [&](const std::vector<Eigen::Vector3d>& v) {
    return [&v](size_t i, double* out) {
      const Eigen::Vector3d w = i < v.size() ? v[i] : Eigen::Vector3d::Zero();
      out[0] = w.x(), out[1] = w.y(), out[2] = w.z();
    };
  };
  add("force", 3, vec(f.force));
  add("drag", 3, vec(f.drag));
  add("contact", 3, vec(f.contact));
  add("flow_velocity", 3, vec(f.flow_velocity));
  const std::string name = fmt::format("{}_{:05d}.vtp", name_, frame_count_ - 1);
  write_atomically(dir_ / name, [&](const std::filesystem::path& tmp) {
    vtkNew<vtkXMLPolyDataWriter> w;
    w->SetFileName(tmp.string().c_str());
    w->SetInputData(poly);
    w->SetDataModeToAppended();
    // A failed write is reported once, here, not also as VTK's multi-line log.
    const int shown = vtkObject::GetGlobalWarningDisplay();
    vtkObject::GlobalWarningDisplayOff();
    const bool written = w->Write() == 1 && w->GetErrorCode() == 0;
    vtkObject::SetGlobalWarningDisplay(shown);
    if (!written) throw_input_error((dir_ / name).string(), "VTK could not write the file (disk full?)");
  });
  vtk_files_.emplace_back(f.time, name);
#endif
}

void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& files) {
  std::string x = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const auto& [t, f] : files) x += fmt::format("    <DataSet timestep=\"{:.9g}\" file=\"{}\"/>\n", t, f);
  x += "  </Collection>\n</VTKFile>\n";
  write_text_atomically(path, x);
}

void WireOutput::finish() {
  if (csv_) {
    write_text_atomically(dir_ / (name_ + ".csv"), wire_csv_);
    if (name_ == "wire") {
      write_text_atomically(dir_ / "tip_trace.csv", tip_csv_);
      write_text_atomically(dir_ / "base_force.csv", base_csv_);
    }
  }
  if (vtk_ && !vtk_files_.empty()) write_pvd(dir_ / (name_ + ".pvd"), vtk_files_);
}

}  // namespace flowire::coupling
