// The PNG of a network (flow/src/render.cpp), read back with VTK's PNG reader: its size, a
// white background, and the colour scale along a tube whose pressure falls linearly from
// left to right (red where high, green halfway, blue where low). Needs an X display: the
// default run has it under xvfb-run; flow_render_xvfb runs these alone under their own.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>

#include "flow_test_networks.hpp"
#include "flowire/flow/output.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

#ifdef FLOWIRE_TEST_HAVE_VTK
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#endif

namespace flowire::flow {
namespace {

using namespace flowire::flow::test;

TEST(FlowRender, PressureColouredPng) {
#ifndef FLOWIRE_TEST_HAVE_VTK
  GTEST_SKIP() << "built without VTK";
#endif
  if (!std::getenv("DISPLAY")) GTEST_SKIP() << "no X display: run under xvfb-run -a -s \"-screen 0 1024x768x24\"";
  const auto dir = flowire::testing::scratch_dir("flow_render");
  const Network net = murray_tree(4);
  auto s = make_solver(net, default_spec(net, Waveform::constant(13000.0)));
  std::vector<double> p(static_cast<size_t>(net.num_nodes()));
  s->node_pressures(p);
  RenderOptions opt;
  opt.title = "Murray tree, 13 kPa inlet";
  opt.view_direction = Vec3(0, 0, -1);
  opt.view_up = Vec3(0, 1, 0);
  opt.overlays.push_back({{net.node(0), net.node(1), net.node(2)}, 0.3e-3, {0.0, 0.0, 0.0}});
  render_network_png(net, p, dir / "pressure.png", opt);
  ASSERT_TRUE(std::filesystem::exists(dir / "pressure.png"));
  EXPECT_GT(std::filesystem::file_size(dir / "pressure.png"), 5000u);
}

TEST(FlowRender, AColourScaleFromRedToBlueAlongAFallingPressure) {
#ifndef FLOWIRE_TEST_HAVE_VTK
  GTEST_SKIP() << "built without VTK";
#else
  if (!std::getenv("DISPLAY")) GTEST_SKIP() << "no X display: run under xvfb-run -a -s \"-screen 0 1024x768x24\"";
  const auto dir = flowire::testing::scratch_dir("flow_render_scale");
  // A tube along +x seen from +z (x to the right), 100 mmHg at its left end, 0 at its right.
  const Network net = tube(0.1, 4e-3, 20);
  std::vector<double> p(static_cast<size_t>(net.num_nodes()));
  for (int i = 0; i < net.num_nodes(); ++i)
    p[static_cast<size_t>(i)] = 100.0 * 133.322387415 * (1.0 - net.node(i).x() / 0.1);
  RenderOptions opt;
  opt.width = 400;
  opt.height = 300;
  opt.view_direction = Vec3(0, 0, -1);
  opt.view_up = Vec3(0, 1, 0);
  render_network_png(net, p, dir / "tube.png", opt);
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName((dir / "tube.png").string().c_str());
  reader->Update();
  vtkImageData* img = reader->GetOutput();
  int dims[3];
  img->GetDimensions(dims);
  ASSERT_EQ(dims[0], 400);
  ASSERT_EQ(dims[1], 300);
  ASSERT_GE(img->GetNumberOfScalarComponents(), 3);
  auto rgb = [&](int x, int y) {
    return std::array<double, 3>{img->GetScalarComponentAsDouble(x, y, 0, 0),
                                 img->GetScalarComponentAsDouble(x, y, 0, 1),
                                 img->GetScalarComponentAsDouble(x, y, 0, 2)};
  };
  auto white = [](const std::array<double, 3>& c) { return c[0] > 250 && c[1] > 250 && c[2] > 250; };
  EXPECT_TRUE(white(rgb(2, 2)));  // background
  // The tube's pixels on the middle row, left of the colour bar (which starts at 88 % of the width).
  const int row = dims[1] / 2;
  int first = -1, last = -1;
  for (int x = 0; x < static_cast<int>(0.85 * dims[0]); ++x)
    if (!white(rgb(x, row))) {
      if (first < 0) first = x;
      last = x;
    }
  ASSERT_GT(last - first, dims[0] / 3) << "the tube does not cross the picture";
  const auto left = rgb(first + 3, row), mid = rgb((first + last) / 2, row), right = rgb(last - 3, row);
  EXPECT_GT(left[0], 2 * left[2]) << "high pressure is not red: " << left[0] << ' ' << left[1] << ' ' << left[2];
  EXPECT_GT(right[2], 2 * right[0]) << "low pressure is not blue: " << right[0] << ' ' << right[1] << ' ' << right[2];
  EXPECT_GT(mid[1], 1.5 * std::max(mid[0], mid[2]))
      << "halfway is not green: " << mid[0] << ' ' << mid[1] << ' ' << mid[2];
#endif
}

}  // namespace
}  // namespace flowire::flow
