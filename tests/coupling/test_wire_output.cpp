// Wire outputs (coupling/src/wire_output.cpp): the CSV files read back to the numbers given,
// the VTK frames read back by VTK's own reader, the .pvd collection parsed as XML, and
// which files exist for a wire, a catheter, and with an output kind off.
#include "flowire/coupling/wire_output.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "flowire_test.hpp"

#ifdef FLOWIRE_TEST_HAVE_VTK
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLDataParser.h>
#include <vtkXMLPolyDataReader.h>
#endif

using namespace flowire::coupling;
using Vec3 = Eigen::Vector3d;
namespace fs = std::filesystem;

namespace {

/// A CSV file: the header and the rows as numbers.
struct Csv {
  std::string header;
  std::vector<std::vector<double>> rows;
};

Csv read_csv(const fs::path& p) {
  std::ifstream in(p);
  EXPECT_TRUE(in) << p;
  Csv c;
  std::getline(in, c.header);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) row.push_back(std::stod(cell));
    c.rows.push_back(row);
  }
  return c;
}

WireFrame frame(double time, int n, double shift) {
  WireFrame f;
  f.time = time;
  for (int i = 0; i < n; ++i) {
    f.x.push_back(Vec3(0.01 * i + shift, -0.002 * i, 1e-4 * i * i));
    f.s.push_back(0.01 * i);
    f.drag.push_back(Vec3(1e-4 * i, 2e-5, -3e-6 * i));
    f.contact.push_back(Vec3(0.0, 0.5 * i, 0.25));
    f.force.push_back(f.drag.back() + f.contact.back());
    f.flow_velocity.push_back(Vec3(0.3, 0.0, -0.1 * i));
  }
  return f;
}

TEST(WireOutput, CsvFilesHoldTheFramesTipAndBaseRows) {
  const auto dir = flowire::testing::scratch_dir("wire_output_csv");
  WireOutput out(dir, true, false);
  WireFrame a = frame(0.0, 3, 0.0);
  a.contact.clear();  // missing per-vertex vectors are written as zeros
  out.add_frame(a);
  out.add_frame(frame(0.25, 4, 0.123456789));
  out.add_tip(0.0, 0.01, Vec3(1, 2, 3));
  out.add_tip(1e-3, 0.0100123, Vec3(1.5, -2.25, 3.125));
  out.add_base(1e-3, Vec3(0.1, -0.2, 0.3), Vec3(-4e-3, 5e-3, 6e-3));
  EXPECT_EQ(out.frames(), 2);
  EXPECT_FALSE(fs::exists(dir / "wire.csv"));  // written at finish
  out.finish();

  const auto w = read_csv(dir / "wire.csv");
  EXPECT_EQ(w.header, "time,vertex,s,x,y,z,drag_x,drag_y,drag_z,contact_x,contact_y,contact_z");
  ASSERT_EQ(w.rows.size(), 7u);
  const WireFrame b = frame(0.25, 4, 0.123456789);
  for (int i = 0; i < 4; ++i) {
    const auto& r = w.rows[static_cast<size_t>(3 + i)];
    ASSERT_EQ(r.size(), 12u);
    EXPECT_EQ(r[0], 0.25);
    EXPECT_EQ(r[1], i);
    EXPECT_NEAR(r[2], b.s[static_cast<size_t>(i)], 1e-12);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(r[static_cast<size_t>(3 + k)], b.x[static_cast<size_t>(i)][k], 1e-9);  // 9 significant digits
      EXPECT_NEAR(r[static_cast<size_t>(6 + k)], b.drag[static_cast<size_t>(i)][k], 1e-6 * 1e-4 * 4);
      EXPECT_NEAR(r[static_cast<size_t>(9 + k)], b.contact[static_cast<size_t>(i)][k], 1e-6 * 2);
    }
  }
  for (int i = 0; i < 3; ++i) EXPECT_EQ(w.rows[static_cast<size_t>(i)][10], 0.0);

  const auto t = read_csv(dir / "tip_trace.csv");
  EXPECT_EQ(t.header, "time,inserted_length,x,y,z");
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[1], (std::vector<double>{1e-3, 0.0100123, 1.5, -2.25, 3.125}));
  const auto base = read_csv(dir / "base_force.csv");
  EXPECT_EQ(base.header, "time,fx,fy,fz,tx,ty,tz");
  ASSERT_EQ(base.rows.size(), 1u);
  EXPECT_EQ(base.rows[0], (std::vector<double>{1e-3, 0.1, -0.2, 0.3, -4e-3, 5e-3, 6e-3}));
}

TEST(WireOutput, ACathetersOutputHasItsOwnNameAndNoTipOrBaseFiles) {
  const auto dir = flowire::testing::scratch_dir("wire_output_catheter");
  WireOutput out(dir, true, false, "catheter");
  out.add_frame(frame(0.0, 2, 0.0));
  out.add_tip(0.0, 0.0, Vec3::Zero());
  out.add_base(0.0, Vec3::Zero(), Vec3::Zero());
  out.finish();
  EXPECT_EQ(read_csv(dir / "catheter.csv").rows.size(), 2u);
  EXPECT_FALSE(fs::exists(dir / "wire.csv"));
  EXPECT_FALSE(fs::exists(dir / "tip_trace.csv"));
  EXPECT_FALSE(fs::exists(dir / "base_force.csv"));
}

TEST(WireOutput, NothingIsWrittenWithBothOutputsOff) {
  const auto dir = flowire::testing::scratch_dir("wire_output_off");
  WireOutput out(dir, false, false);
  out.add_frame(frame(0.0, 3, 0.0));
  out.add_tip(0.0, 0.0, Vec3::Zero());
  out.finish();
  EXPECT_EQ(out.frames(), 1);
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(WireOutput, PvdListsEveryFileWithItsTime) {
  const auto dir = flowire::testing::scratch_dir("wire_output_pvd");
  write_pvd(dir / "series.pvd", {{0.0, "a_00000.vtp"}, {0.123456789012, "a_00001.vtp"}, {2.5, "a_00002.vtp"}});
  std::ifstream in(dir / "series.pvd");
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  const std::regex entry(R"re(<DataSet timestep="([^"]*)" file="([^"]*)"/>)re");
  std::vector<std::pair<double, std::string>> got;
  for (auto it = std::sregex_iterator(s.begin(), s.end(), entry); it != std::sregex_iterator(); ++it)
    got.emplace_back(std::stod((*it)[1]), (*it)[2]);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_NEAR(got[1].first, 0.123456789012, 1e-9);
  EXPECT_EQ(got[2].second, "a_00002.vtp");
  EXPECT_NE(s.find("<VTKFile type=\"Collection\""), std::string::npos);
#ifdef FLOWIRE_TEST_HAVE_VTK
  // VTK's own XML parser accepts it.
  vtkNew<vtkXMLDataParser> parser;
  parser->SetFileName((dir / "series.pvd").string().c_str());
  ASSERT_EQ(parser->Parse(), 1);
  vtkXMLDataElement* root = parser->GetRootElement();
  ASSERT_NE(root, nullptr);
  EXPECT_STREQ(root->GetAttribute("type"), "Collection");
  ASSERT_EQ(root->GetNumberOfNestedElements(), 1);
  EXPECT_EQ(root->GetNestedElement(0)->GetNumberOfNestedElements(), 3);
#endif
}

#ifdef FLOWIRE_TEST_HAVE_VTK
TEST(WireOutput, VtkFramesReadBackThroughVtk) {
  const auto dir = flowire::testing::scratch_dir("wire_output_vtk");
  WireOutput out(dir, false, true);
  WireFrame a = frame(0.0, 5, 0.0), b = frame(0.5, 6, 0.01);
  b.flow_velocity.resize(2);  // vertices past the end of a short vector get zeros
  out.add_frame(a);
  out.add_frame(b);
  out.finish();
  EXPECT_TRUE(fs::exists(dir / "wire.pvd"));
  EXPECT_FALSE(fs::exists(dir / "wire.csv"));
  vtkNew<vtkXMLPolyDataReader> r;
  r->SetFileName((dir / "wire_00001.vtp").string().c_str());
  r->Update();
  vtkPolyData* pd = r->GetOutput();
  ASSERT_EQ(pd->GetNumberOfPoints(), 6);
  ASSERT_EQ(pd->GetNumberOfLines(), 1);  // one polyline through every vertex
  EXPECT_EQ(pd->GetCell(0)->GetNumberOfPoints(), 6);
  for (int i = 0; i < 6; ++i) {
    double x[3];
    pd->GetPoint(i, x);
    EXPECT_EQ(Vec3(x[0], x[1], x[2]), b.x[static_cast<size_t>(i)]);  // doubles, exactly
  }
  auto array = [&](const char* name, int comps) {
    vtkDataArray* arr = pd->GetPointData()->GetArray(name);
    EXPECT_NE(arr, nullptr) << name;
    if (arr) {
      EXPECT_EQ(arr->GetNumberOfComponents(), comps) << name;
    }
    return arr;
  };
  vtkDataArray* s = array("s", 1);
  vtkDataArray* force = array("force", 3);
  vtkDataArray* contact = array("contact", 3);
  vtkDataArray* drag = array("drag", 3);
  vtkDataArray* u = array("flow_velocity", 3);
  ASSERT_TRUE(s && force && contact && drag && u);
  for (int i = 0; i < 6; ++i) {
    const auto k = static_cast<size_t>(i);
    EXPECT_EQ(s->GetTuple1(i), b.s[k]);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(force->GetComponent(i, c), b.force[k][c]);
      EXPECT_EQ(drag->GetComponent(i, c), b.drag[k][c]);
      EXPECT_EQ(contact->GetComponent(i, c), b.contact[k][c]);
      EXPECT_EQ(u->GetComponent(i, c), i < 2 ? b.flow_velocity[k][c] : 0.0);
    }
  }
}
#endif

}  // namespace
