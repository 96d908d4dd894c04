// The quadratic tetrahedral mesh written as .vtu (mesh/src/vtu.cpp) read back by VTK's own
// reader: the points, the quadratic tetrahedra and the point data ParaView will show.
#include "flowire/mesh/vtu.hpp"

#include <gtest/gtest.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "flowire/common/error.hpp"
#include "flowire/solid/tube_wall.hpp"
#include "flowire_test.hpp"

namespace flowire::mesh {
namespace {

TEST(MeshVtu, VtkReadsBackTheQuadraticTetrahedraAndTheirPointData) {
  const TetMesh m = solid::mesh_tube_wall({2e-3, 2.5e-3, 3e-3, 1e-3, true});
  PointField radius{"radius", 1, {}}, shift{"shift", 3, {}};
  for (const Vec3& x : m.nodes) {
    radius.values.push_back(std::hypot(x.x(), x.y()));
    shift.values.insert(shift.values.end(), {x.z(), 2 * x.z(), 3 * x.z()});
  }
  const auto path = testing::scratch_dir("mesh_vtu") / "wall.vtu";
  write_vtu(path, m, {radius, shift});
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  ASSERT_EQ(grid->GetNumberOfPoints(), m.num_nodes());
  ASSERT_EQ(grid->GetNumberOfCells(), m.num_tets());
  EXPECT_EQ(grid->GetCellType(0), 24);  // VTK_QUADRATIC_TETRA
  vtkDataArray* r = grid->GetPointData()->GetArray("radius");
  vtkDataArray* s = grid->GetPointData()->GetArray("shift");
  ASSERT_NE(r, nullptr);
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->GetNumberOfComponents(), 3);
  for (vtkIdType n = 0; n < grid->GetNumberOfPoints(); n += 37) {
    double p[3];
    grid->GetPoint(n, p);
    EXPECT_NEAR(r->GetTuple1(n), std::hypot(p[0], p[1]), 1e-9 * std::hypot(p[0], p[1]));  // 10 digits written
    EXPECT_NEAR(s->GetComponent(n, 2), 3 * p[2], 1e-9 * std::abs(3 * p[2]) + 1e-15);
  }
  // A field of the wrong size is refused, nothing written.
  PointField bad{"bad", 3, {1.0, 2.0}};
  const auto bad_path = testing::scratch_dir("mesh_vtu") / "bad.vtu";
  EXPECT_THROW(write_vtu(bad_path, m, {bad}), Error);
  EXPECT_FALSE(std::filesystem::exists(bad_path));
}

}  // namespace
}  // namespace flowire::mesh
