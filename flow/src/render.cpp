// Offscreen VTK rendering of the network as tubes coloured by a node scalar.
#include <fmt/format.h>

#include <cstdlib>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/output.hpp"

#ifdef FLOWIRE_FLOW_HAVE_VTK
#include <X11/Xlib.h>
#include <vtkActor.h>
#include <vtkAxis.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#undef Status
#undef None
#undef Bool
#undef Success
#include <vtkRenderWindow.h>

#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkTubeFilter.h>
#include <vtkWindowToImageFilter.h>
#include <chrono>
#include <thread>
#endif

namespace flowire::flow {

#ifdef FLOWIRE_FLOW_HAVE_VTK
namespace {

vtkNew<vtkActor> tube_actor(vtkPolyData* poly, double radius_scale, int sides) {
  vtkNew<vtkTubeFilter> tube;
  tube->SetInputData(poly);
  tube->SetNumberOfSides(sides);
  tube->SetRadius(radius_scale);
  tube->CappingOn();
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputConnection(tube->GetOutputPort());
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  return actor;
}

/// The X connection a render needs. VTK aborts the process when it cannot open the display:
/// it is opened here and handed to the render window (which then opens none of its own; a
/// second connection per render occasionally failed under a busy Xvfb), and closed after
/// the window is gone.
struct XConnection {
  Display* d = nullptr;
  XConnection() = default;
  XConnection(const XConnection&) = delete;
  XConnection& operator=(const XConnection&) = delete;
  XConnection(XConnection&& o) noexcept : d(o.d) { o.d = nullptr; }
  XConnection& operator=(XConnection&&) = delete;
  ~XConnection() {
    if (d) XCloseDisplay(d);
  }
};

XConnection connect_display(const std::string& where) {
  const char* display = std::getenv("DISPLAY");
  if (!display || !*display)
    throw_input_error(where, "rendering a PNG needs an X display; run under xvfb-run -a -s \"-screen 0 1024x768x24\"");
  XConnection x;
  for (int attempt = 0; attempt < 5 && !x.d; ++attempt) {
    x.d = XOpenDisplay(nullptr);
    if (!x.d) std::this_thread::sleep_for(std::chrono::milliseconds(100 << attempt));
  }
  if (!x.d)
    throw_input_error(where, fmt::format("cannot connect to the X display '{}'; run under xvfb-run -a", display));
  return x;
}

/// The rendered window as a PNG at @p path, written atomically.
void write_window_png(vtkRenderWindow* win, const std::filesystem::path& path) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(win);
  grab->ReadFrontBufferOff();
  grab->Update();
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    vtkNew<vtkPNGWriter> png;
    png->SetFileName(tmp.string().c_str());
    png->SetInputConnection(grab->GetOutputPort());
    png->Write();
    if (png->GetErrorCode() != 0 || !std::filesystem::exists(tmp) || std::filesystem::file_size(tmp) == 0)
      throw_input_error(path.string(), "the PNG could not be written");
  });
}

}  // namespace
#endif

void check_can_render(const std::string& where) {
#ifndef FLOWIRE_FLOW_HAVE_VTK
  throw_input_error(where, "PNG rendering needs VTK (this build has FLOWIRE_WITH_VTK=OFF)");
#else
  (void)connect_display(where);
#endif
}

void render_network_png(const Network& net, std::span<const double> node_values, const std::filesystem::path& path,
                        const RenderOptions& opt) {
#ifndef FLOWIRE_FLOW_HAVE_VTK
  (void)net, (void)node_values, (void)opt;
  throw_input_error(path.string(), "PNG rendering needs VTK (this build has FLOWIRE_WITH_VTK=OFF)");
#else
  if (node_values.size() != static_cast<size_t>(net.num_nodes()))
    throw_usage_error("render_network_png: node_values must have one value per node");
  const XConnection x = connect_display(path.string());

  // Vessels: one polydata, tubes of radius varying with the node radius.
  vtkNew<vtkPoints> pts;
  pts->SetNumberOfPoints(net.num_nodes());
  for (int i = 0; i < net.num_nodes(); ++i) pts->SetPoint(i, net.node(i).data());
  // One polyline per branch (tubes then join smoothly inside a branch); segments that no
  // branch lists are drawn alone.
  vtkNew<vtkCellArray> lines;
  std::vector<char> drawn(static_cast<size_t>(net.num_segments()), 0);
  for (const auto& b : net.branches()) {
    if (b.nodes.size() < 2 || b.nodes.size() != b.segments.size() + 1) continue;
    lines->InsertNextCell(static_cast<vtkIdType>(b.nodes.size()));
    for (int n : b.nodes) lines->InsertCellPoint(n);
    for (int s : b.segments) drawn[static_cast<size_t>(s)] = 1;
  }
  for (int s = 0; s < net.num_segments(); ++s) {
    if (drawn[static_cast<size_t>(s)]) continue;
    const vtkIdType ids[2] = {net.segment(s).node_from, net.segment(s).node_to};
    lines->InsertNextCell(2, ids);
  }
  vtkNew<vtkDoubleArray> scalars;
  scalars->SetName("value");
  scalars->SetNumberOfTuples(net.num_nodes());
  double lo = 1e300, hi = -1e300;
  for (int i = 0; i < net.num_nodes(); ++i) {
    const double v = node_values[static_cast<size_t>(i)] * opt.scalar_scale;
    scalars->SetValue(i, v);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (opt.range_max > opt.range_min) lo = opt.range_min, hi = opt.range_max;
  if (!(hi > lo)) hi = lo + 1.0;
  vtkNew<vtkDoubleArray> radius;
  radius->SetName("radius");
  radius->SetNumberOfTuples(net.num_nodes());
  for (int i = 0; i < net.num_nodes(); ++i) {
    double r = 0.0;
    int n = 0;
    const auto [b, e] = net.node_segments(i);
    for (const int* p = b; p != e; ++p, ++n) r += net.segment(*p).radius;
    radius->SetValue(i, n ? r / n : 1e-3);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(pts);
  poly->SetLines(lines);
  poly->GetPointData()->AddArray(radius);
  poly->GetPointData()->AddArray(scalars);
  poly->GetPointData()->SetActiveScalars("radius");

  vtkNew<vtkTubeFilter> tube;
  tube->SetInputData(poly);
  tube->SetNumberOfSides(16);
  tube->SetVaryRadiusToVaryRadiusByAbsoluteScalar();
  tube->CappingOn();
  vtkNew<vtkLookupTable> lut;
  lut->SetHueRange(0.667, 0.0);  // blue (low) to red (high)
  lut->SetTableRange(lo, hi);
  lut->Build();
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputConnection(tube->GetOutputPort());
  mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectColorArray("value");
  mapper->SetLookupTable(lut);
  mapper->SetScalarRange(lo, hi);
  mapper->ScalarVisibilityOn();
  vtkNew<vtkActor> vessels_actor;
  vessels_actor->SetMapper(mapper);
  // Translucent vessels when something is drawn inside them (the wire).
  if (!opt.overlays.empty()) vessels_actor->GetProperty()->SetOpacity(0.35);

  vtkNew<vtkRenderer> ren;
  ren->SetBackground(1.0, 1.0, 1.0);
  ren->AddActor(vessels_actor);

  std::vector<vtkSmartPointer<vtkPolyData> > keep;
  for (const auto& ov : opt.overlays) {
    if (ov.points.size() < 2) continue;
    auto p = vtkSmartPointer<vtkPolyData>::New();
    vtkNew<vtkPoints> op;
    vtkNew<vtkCellArray> ol;
    ol->InsertNextCell(static_cast<vtkIdType>(ov.points.size()));
    for (size_t i = 0; i < ov.points.size(); ++i) ol->InsertCellPoint(op->InsertNextPoint(ov.points[i].data()));
    p->SetPoints(op);
    p->SetLines(ol);
    keep.push_back(p);
    auto actor = tube_actor(p, ov.radius, 12);
    actor->GetProperty()->SetColor(ov.color[0], ov.color[1], ov.color[2]);
    ren->AddActor(actor);
  }

  vtkNew<vtkScalarBarActor> bar;
  bar->SetLookupTable(lut);
  bar->SetTitle(opt.scalar_name.c_str());
  bar->SetNumberOfLabels(5);
  bar->SetLabelFormat(hi - lo < 10.0 ? "%.2f" : "%.0f");
  bar->GetTitleTextProperty()->SetColor(0, 0, 0);
  bar->GetLabelTextProperty()->SetColor(0, 0, 0);
  bar->SetWidth(0.1);
  bar->SetHeight(0.6);
  bar->SetPosition(0.88, 0.2);
  ren->AddActor2D(bar);
  vtkNew<vtkTextActor> title;
  if (!opt.title.empty()) {
    title->SetInput(opt.title.c_str());
    title->GetTextProperty()->SetColor(0, 0, 0);
    title->GetTextProperty()->SetFontSize(20);
    title->SetDisplayPosition(10, opt.height - 30);
    ren->AddActor2D(title);
  }

  auto* cam = ren->GetActiveCamera();
  cam->SetFocalPoint(0, 0, 0);
  cam->SetPosition(-opt.view_direction.x(), -opt.view_direction.y(), -opt.view_direction.z());
  cam->SetViewUp(opt.view_up.x(), opt.view_up.y(), opt.view_up.z());
  ren->ResetCamera();

  vtkNew<vtkRenderWindow> win;
  win->SetDisplayId(x.d);
  win->SetOffScreenRendering(1);
  win->SetSize(opt.width, opt.height);
  win->AddRenderer(ren);
  win->Render();
  write_window_png(win, path);
  win->Finalize();  // release the window's X resources before the connection closes
#endif
}

void render_waveforms_png(const std::vector<WaveformSeries>& series, const std::string& title,
                          const std::filesystem::path& path, int width, int height) {
#ifndef FLOWIRE_FLOW_HAVE_VTK
  (void)series, (void)title, (void)width, (void)height;
  throw_input_error(path.string(), "PNG rendering needs VTK (this build has FLOWIRE_WITH_VTK=OFF)");
#else
  if (series.empty()) throw_usage_error("render_waveforms_png: no series");
  const XConnection x = connect_display(path.string());
  // Two charts one above the other in one image: pressure (mmHg) and flow (mL/s) over time,
  // a line per series in a colour of its own (the 1D papers' figure of a model's waveforms).
  vtkNew<vtkContextView> view;
  view->GetRenderWindow()->SetDisplayId(x.d);
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetSize(width, height);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  static const unsigned char colours[][3] = {{31, 119, 180},  {255, 127, 14}, {44, 160, 44},   {214, 39, 40},
                                             {148, 103, 189}, {140, 86, 75},  {227, 119, 194}, {127, 127, 127}};
  std::vector<vtkSmartPointer<vtkTable> > tables;
  for (int panel = 0; panel < 2; ++panel) {
    vtkNew<vtkChartXY> chart;
    const bool pressure = panel == 0;
    const float lo = pressure ? 0.52f : 0.04f;
    chart->SetAutoSize(false);
    chart->SetSize(
        vtkRectf(0.0f, lo * static_cast<float>(height), static_cast<float>(width), 0.44f * static_cast<float>(height)));
    chart->SetTitle(pressure ? title + ": pressure" : "flow");
    chart->GetAxis(vtkAxis::BOTTOM)->SetTitle("time in the last cycle (s)");
    chart->GetAxis(vtkAxis::LEFT)->SetTitle(pressure ? "pressure (mmHg)" : "flow (mL/s)");
    chart->SetShowLegend(pressure);
    if (pressure) chart->GetLegend()->SetHorizontalAlignment(vtkChartLegend::RIGHT);
    for (size_t k = 0; k < series.size(); ++k) {
      const auto& s = series[k];
      if (s.time.size() != s.pressure.size() || s.time.size() != s.flow.size() || s.time.size() < 2)
        throw_usage_error(fmt::format("render_waveforms_png: series '{}' has mismatched or too few samples", s.name));
      auto t = vtkSmartPointer<vtkTable>::New();
      vtkNew<vtkFloatArray> xs, ys;
      xs->SetName("t");
      ys->SetName(s.name.c_str());
      t->AddColumn(xs);
      t->AddColumn(ys);
      t->SetNumberOfRows(static_cast<vtkIdType>(s.time.size()));
      for (size_t i = 0; i < s.time.size(); ++i) {
        t->SetValue(static_cast<vtkIdType>(i), 0, s.time[i]);
        t->SetValue(static_cast<vtkIdType>(i), 1, pressure ? s.pressure[i] / 133.322387415 : s.flow[i] * 1e6);
      }
      tables.push_back(t);
      vtkPlot* line = chart->AddPlot(vtkChart::LINE);
      line->SetInputData(t, 0, 1);
      const auto* c = colours[k % (sizeof(colours) / sizeof(colours[0]))];
      line->SetColor(c[0], c[1], c[2], 255);
      line->SetWidth(2.0f);
    }
    view->GetScene()->AddItem(chart);
  }
  view->GetRenderWindow()->Render();
  write_window_png(view->GetRenderWindow(), path);
  view->GetRenderWindow()->Finalize();
#endif
}

}  // namespace flowire::flow
