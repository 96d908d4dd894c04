// Reading triangulated lumen surfaces (.vtp, .stl, .obj) with VTK's readers. VTK's own
// messages are kept off stderr while a file is read; an error becomes one flowire::Error
// naming the file.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <mutex>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/vessels/surface.hpp"

#ifdef FLOWIRE_HAVE_VTK
#include <vtkAlgorithm.h>
#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCommand.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkOBJReader.h>
#include <vtkObject.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkXMLPolyDataReader.h>
#endif

namespace flowire::vessels {

#ifdef FLOWIRE_HAVE_VTK
namespace {

void on_error(vtkObject*, unsigned long, void* client, void* call) {
  auto* msg = static_cast<std::string*>(client);
  if (msg->empty()) *msg = call ? static_cast<const char*>(call) : "unknown error";
}

SurfaceMesh run(vtkAlgorithm* reader, vtkPolyData* (*output)(vtkAlgorithm*), const std::string& path, double factor) {
  static std::mutex mutex;  // VTK's global warning switch
  const std::lock_guard lock(mutex);
  std::string error;
  vtkNew<vtkCallbackCommand> cb;
  cb->SetCallback(on_error);
  cb->SetClientData(&error);
  reader->AddObserver(vtkCommand::ErrorEvent, cb);
  const int shown = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  reader->Update();
  vtkObject::SetGlobalWarningDisplay(shown);
  if (!error.empty()) {
    while (!error.empty() && (error.back() == '\n' || error.back() == ' ')) error.pop_back();
    const auto nl = error.find_last_of('\n');
    if (nl != std::string::npos) error = error.substr(nl + 1);
    throw_input_error(path, fmt::format("cannot read the surface: {}", error.substr(0, 300)));
  }
  vtkPolyData* pd = output(reader);
  if (!pd) throw_input_error(path, "VTK read no poly data from the file");
  SurfaceMesh m;
  m.source = path;
  m.vertices.resize(static_cast<size_t>(pd->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < pd->GetNumberOfPoints(); ++i) {
    double x[3];
    pd->GetPoint(i, x);
    const Vec3 p(x[0], x[1], x[2]);
    if (!p.allFinite()) throw_input_error(path, fmt::format("point {}: coordinate is not finite", i));
    m.vertices[static_cast<size_t>(i)] = factor * p;
  }
  if (vtkCellArray* polys = pd->GetPolys()) {
    vtkNew<vtkIdList> ids;
    polys->InitTraversal();
    while (polys->GetNextCell(ids)) {
      // Polygons as fans (VTK polygons are convex by convention).
      for (vtkIdType k = 1; k + 1 < ids->GetNumberOfIds(); ++k)
        m.triangles.push_back(
            {static_cast<int>(ids->GetId(0)), static_cast<int>(ids->GetId(k)), static_cast<int>(ids->GetId(k + 1))});
    }
  }
  if (vtkCellArray* strips = pd->GetStrips()) {
    vtkNew<vtkIdList> ids;
    strips->InitTraversal();
    while (strips->GetNextCell(ids))
      for (vtkIdType k = 0; k + 2 < ids->GetNumberOfIds(); ++k) {
        std::array<int, 3> t{static_cast<int>(ids->GetId(k)), static_cast<int>(ids->GetId(k + 1)),
                             static_cast<int>(ids->GetId(k + 2))};
        if (k % 2) std::swap(t[1], t[2]);
        m.triangles.push_back(t);
      }
  }
  if (m.triangles.empty())
    throw_input_error(path, fmt::format("the file has no triangles ({} points, {} lines): a lumen surface is a "
                                        "triangulated wall, not a centerline",
                                        pd->GetNumberOfPoints(), pd->GetNumberOfLines()));
  return m;
}

template <class R>
vtkPolyData* output_of(vtkAlgorithm* a) {
  return static_cast<R*>(a)->GetOutput();
}

}  // namespace
#endif

SurfaceMesh read_surface(const std::string& path, double length_factor) {
  check_input_file(path, input_limit::kGeometry, "a lumen surface");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (size == 0) throw_input_error(path, "the surface file is empty");
  std::string ext = std::filesystem::path(path).extension().string();
  for (auto& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (ext != ".vtp" && ext != ".stl" && ext != ".obj")
    throw_input_error(path, fmt::format("unknown surface format '{}' (read: .vtp, .stl, .obj)", ext));
  if (!(length_factor > 0.0) || !std::isfinite(length_factor))
    throw_usage_error("read_surface: length_factor must be > 0");
#ifdef FLOWIRE_HAVE_VTK
  if (ext == ".vtp") {
    vtkNew<vtkXMLPolyDataReader> r;
    if (!r->CanReadFile(path.c_str())) throw_input_error(path, "not a VTK XML poly data file");
    r->SetFileName(path.c_str());
    return run(r, output_of<vtkXMLPolyDataReader>, path, length_factor);
  }
  if (ext == ".stl") {
    vtkNew<vtkSTLReader> r;
    r->SetFileName(path.c_str());
    r->MergingOff();  // merged exactly by LumenSurface
    return run(r, output_of<vtkSTLReader>, path, length_factor);
  }
  vtkNew<vtkOBJReader> r;
  r->SetFileName(path.c_str());
  return run(r, output_of<vtkOBJReader>, path, length_factor);
#else
  throw_input_error(path, "this flowire was built without VTK (FLOWIRE_WITH_VTK=OFF): it cannot read surfaces");
#endif
}

}  // namespace flowire::vessels
