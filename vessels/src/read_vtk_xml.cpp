// VTK XML poly data (.vtp, ASCII, binary or appended, compressed or not) read with VTK's
// vtkXMLPolyDataReader into PolyData: points, line cells, and the numeric point, cell (of the
// line cells only: VTK numbers vertex cells first) and field arrays, with string field arrays.
// Before VTK sees a file its declared counts are checked against its size (check_declared_sizes).
// VTK reports problems through its output window and error events; while a file is read
// both are captured, nothing reaches stderr, and the first error becomes one flowire::Error.
// Without VTK (FLOWIRE_WITH_VTK=OFF) reading a .vtp is an error saying so.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <string>

#include "flowire/common/error.hpp"
#include "polydata_internal.hpp"

#ifdef FLOWIRE_HAVE_VTK
#include <vtkAbstractArray.h>
#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkXMLPolyDataReader.h>
#endif

namespace flowire::vessels::detail {

/// Counts declared in an XML file (NumberOfPoints, NumberOfLines, NumberOfTuples, ...) must fit
/// in it: a corrupt header must not make VTK allocate gigabytes. Compressed data can be small
/// for many values, hence the generous ratio.
void check_declared_sizes(const std::string& path, const std::string& text, uintmax_t size) {
  const double limit = 1100.0 * static_cast<double>(size) + 1e4;
  for (size_t p = text.find("Number"); p != std::string::npos; p = text.find("Number", p + 1)) {
    size_t q = p;
    while (q < text.size() && std::isalpha(static_cast<unsigned char>(text[q]))) ++q;
    const std::string name = text.substr(p, q - p);
    while (q < text.size() && text[q] == ' ') ++q;
    if (q >= text.size() || text[q] != '=') continue;
    ++q;
    while (q < text.size() && text[q] == ' ') ++q;
    if (q >= text.size() || text[q] != '"') continue;
    ++q;
    const size_t b = q;
    while (q < text.size() && q - b < 32 && text[q] != '"') ++q;
    const std::string value = text.substr(b, q - b);
    char* end = nullptr;
    const double n = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || !(n >= 0.0) || n > limit)
      throw_input_error(path, fmt::format("{}=\"{}\" does not fit in a file of {} bytes (corrupt or truncated file)",
                                          name, value, size));
  }
}

#ifdef FLOWIRE_HAVE_VTK
namespace {

/// Collects VTK's messages instead of printing them.
class CaptureWindow : public vtkOutputWindow {
 public:
  static CaptureWindow* New();
  vtkTypeMacro(CaptureWindow, vtkOutputWindow) void DisplayText(const char* text) override {
    other.emplace_back(text ? text : "");
  }
  void DisplayErrorText(const char* text) override { errors.emplace_back(text ? text : ""); }
  void DisplayWarningText(const char* text) override { other.emplace_back(text ? text : ""); }
  void DisplayGenericWarningText(const char* text) override { other.emplace_back(text ? text : ""); }
  void DisplayDebugText(const char* text) override { other.emplace_back(text ? text : ""); }
  std::vector<std::string> errors, other;
};
vtkStandardNewMacro(CaptureWindow)

    /// Installs a CaptureWindow and silences VTK's logger (which writes to stderr itself) for its
    /// lifetime.
    class CaptureGuard {
 public:
  CaptureGuard() : previous_(vtkOutputWindow::GetInstance()), verbosity_(vtkLogger::GetCurrentVerbosityCutoff()) {
    window_ = vtkSmartPointer<CaptureWindow>::New();
    vtkOutputWindow::SetInstance(window_);
    vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  }
  ~CaptureGuard() {
    vtkLogger::SetStderrVerbosity(verbosity_);
    vtkOutputWindow::SetInstance(previous_);
  }
  CaptureGuard(const CaptureGuard&) = delete;
  CaptureGuard& operator=(const CaptureGuard&) = delete;
  CaptureWindow& window() { return *window_; }

 private:
  vtkSmartPointer<vtkOutputWindow> previous_;
  vtkLogger::Verbosity verbosity_;
  vtkSmartPointer<CaptureWindow> window_;
};

/// The useful part of a VTK message: its last line, without the "vtkClass (0x...): " prefix.
std::string clean_message(const std::string& msg) {
  std::string s = msg;
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  const auto nl = s.find_last_of('\n');
  if (nl != std::string::npos) s = s.substr(nl + 1);
  const auto p = s.find("): ");
  if (p != std::string::npos && p < 80) s = s.substr(p + 3);
  if (s.size() > 300) s = s.substr(0, 300) + "...";
  return s;
}

void on_vtk_event(vtkObject*, unsigned long event, void* client, void* call) {
  auto* window = static_cast<CaptureWindow*>(client);
  const char* text = static_cast<const char*>(call);
  if (event == vtkCommand::ErrorEvent)
    window->errors.emplace_back(text ? text : "");
  else
    window->other.emplace_back(text ? text : "");
}

void copy_arrays(vtkFieldData* in, std::vector<NumericArray>& numeric, std::vector<StringArray>* strings,
                 vtkIdType first_tuple, vtkIdType tuples) {
  if (!in) return;
  for (int i = 0; i < in->GetNumberOfArrays(); ++i) {
    vtkAbstractArray* a = in->GetAbstractArray(i);
    if (!a || !a->GetName()) continue;
    if (auto* d = vtkDataArray::SafeDownCast(a)) {
      NumericArray out;
      out.name = d->GetName();
      out.components = d->GetNumberOfComponents();
      vtkIdType n = d->GetNumberOfTuples();
      vtkIdType begin = 0;
      if (tuples >= 0) {  // cell data of line cells only
        begin = std::min(first_tuple, n);
        n = std::clamp<vtkIdType>(n - begin, 0, tuples);
      }
      out.values.reserve(static_cast<size_t>(n) * static_cast<size_t>(std::max(out.components, 0)));
      for (vtkIdType t = begin; t < begin + n; ++t)
        for (int c = 0; c < out.components; ++c) out.values.push_back(d->GetComponent(t, c));
      numeric.push_back(std::move(out));
    } else if (auto* s = vtkStringArray::SafeDownCast(a); s && strings) {
      StringArray out;
      out.name = s->GetName();
      for (vtkIdType k = 0; k < s->GetNumberOfValues(); ++k) out.values.push_back(s->GetValue(k));
      strings->push_back(std::move(out));
    }
  }
}

PolyData to_polydata(vtkPolyData* pd, const std::string& path) {
  PolyData out;
  out.source = path;
  if (!pd) throw_input_error(path, "VTK read no poly data from the file");
  const vtkIdType np = pd->GetNumberOfPoints();
  out.points.resize(static_cast<size_t>(np));
  for (vtkIdType i = 0; i < np; ++i) {
    double x[3];
    pd->GetPoint(i, x);
    out.points[static_cast<size_t>(i)] = Vec3(x[0], x[1], x[2]);
  }
  if (vtkCellArray* lines = pd->GetLines()) {
    vtkNew<vtkIdList> ids;
    lines->InitTraversal();
    while (lines->GetNextCell(ids)) {
      std::vector<long long> cell(static_cast<size_t>(ids->GetNumberOfIds()));
      for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) cell[static_cast<size_t>(k)] = ids->GetId(k);
      out.lines.push_back(std::move(cell));
    }
  }
  out.other_cells = pd->GetNumberOfVerts() + pd->GetNumberOfPolys() + pd->GetNumberOfStrips();
  copy_arrays(pd->GetPointData(), out.point_data, nullptr, 0, -1);
  // Cell data run over vertices first, then lines.
  copy_arrays(pd->GetCellData(), out.cell_data, nullptr, pd->GetNumberOfVerts(),
              static_cast<vtkIdType>(out.lines.size()));
  copy_arrays(pd->GetFieldData(), out.field_data, &out.field_strings, 0, -1);
  return out;
}

template <class Reader>
PolyData run_reader(Reader* reader, const std::string& path, const char* what) {
  // The output window and the logger verbosity are global: one read at a time.
  static std::mutex mutex;
  const std::lock_guard lock(mutex);
  CaptureGuard guard;
  vtkNew<vtkCallbackCommand> cb;
  cb->SetCallback(on_vtk_event);
  cb->SetClientData(&guard.window());
  reader->AddObserver(vtkCommand::ErrorEvent, cb);
  reader->AddObserver(vtkCommand::WarningEvent, cb);
  reader->SetFileName(path.c_str());
  reader->Update();
  const auto& errors = guard.window().errors;
  if (!errors.empty())
    throw_input_error(path, fmt::format("cannot read the {} file: {}", what, clean_message(errors.front())));
  if (reader->GetErrorCode() != 0)
    throw_input_error(path, fmt::format("cannot read the {} file (VTK error code {})", what, reader->GetErrorCode()));
  return to_polydata(reader->GetOutput(), path);
}

}  // namespace
#endif

PolyData read_vtk_xml_polydata(const std::string& path) {
#ifdef FLOWIRE_HAVE_VTK
  vtkNew<vtkXMLPolyDataReader> reader;
  return run_reader(reader.GetPointer(), path, "VTK XML poly data");
#else
  throw_input_error(path,
                    "this flowire was built without VTK (FLOWIRE_WITH_VTK=OFF): it cannot read .vtp "
                    "files; convert the centerlines to legacy .vtk or flowire YAML");
#endif
}

}  // namespace flowire::vessels::detail
