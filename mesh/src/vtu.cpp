// The quadratic tetrahedral mesh as a .vtu (ASCII XML), written atomically.
#include "flowire/mesh/vtu.hpp"

#include <fmt/format.h>

#include <ostream>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"

namespace flowire::mesh {

void write_vtu(const std::filesystem::path& path, const TetMesh& mesh, const std::vector<PointField>& fields) {
  std::string scalars, vectors;
  for (const PointField& f : fields) {
    if (f.values.size() != mesh.nodes.size() * static_cast<size_t>(f.components))
      throw_usage_error(fmt::format("{}: field '{}' has {} values for {} nodes × {}", path.string(), f.name,
                                    f.values.size(), mesh.nodes.size(), f.components));
    if (f.components == 1 && scalars.empty()) scalars = f.name;
    if (f.components == 3 && vectors.empty()) vectors = f.name;
  }
  write_stream_atomically(path, [&](std::ostream& out) {
    out.precision(10);
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
        << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << mesh.nodes.size() << "\" NumberOfCells=\""
        << mesh.tets.size() << "\">\n<PointData";
    if (!scalars.empty()) out << " Scalars=\"" << scalars << "\"";
    if (!vectors.empty()) out << " Vectors=\"" << vectors << "\"";
    out << ">\n";
    for (const PointField& f : fields) {
      out << "<DataArray type=\"Float64\" Name=\"" << f.name << "\" NumberOfComponents=\"" << f.components
          << "\" format=\"ascii\">\n";
      for (size_t n = 0; n < mesh.nodes.size(); ++n)
        for (int c = 0; c < f.components; ++c)
          out << f.values[n * static_cast<size_t>(f.components) + static_cast<size_t>(c)]
              << (c + 1 == f.components ? '\n' : ' ');
      out << "</DataArray>\n";
    }
    out << "</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (const Vec3& x : mesh.nodes) out << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
    out << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    // VTK_QUADRATIC_TETRA's edge order, (0,1), (1,2), (0,2), (0,3), (1,3), (2,3), is ours.
    for (const auto& t : mesh.tets)
      for (int k = 0; k < 10; ++k) out << t[static_cast<size_t>(k)] << (k == 9 ? '\n' : ' ');
    out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (size_t e = 0; e < mesh.tets.size(); ++e) out << 10 * (e + 1) << '\n';
    out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
    for (size_t e = 0; e < mesh.tets.size(); ++e) out << "24\n";
    out << "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  });
}

}  // namespace flowire::mesh
