// Network writers: VTK XML poly data (.vtp, written directly, no VTK needed) and flowire YAML.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/vessels/io.hpp"

namespace flowire::vessels {
namespace {

std::string xml_escape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// Raw appended data: every array is a UInt64 byte count followed by its bytes.
class Appended {
 public:
  template <class T>
  size_t add(const std::vector<T>& values) {
    const size_t offset = bytes_.size();
    const auto n = static_cast<uint64_t>(values.size() * sizeof(T));
    put(&n, sizeof n);
    if (n > 0) put(values.data(), static_cast<size_t>(n));
    return offset;
  }
  [[nodiscard]] const std::string& bytes() const { return bytes_; }

 private:
  void put(const void* p, size_t n) { bytes_.append(static_cast<const char*>(p), n); }
  std::string bytes_;
};

struct ArrayXml {
  std::string type;  // Float64, Int64, Int32
  std::string name;
  int components = 1;
  size_t tuples = 0;
  size_t offset = 0;
};

std::string array_tag(const ArrayXml& a, bool field) {
  return fmt::format(R"(<DataArray type="{}" Name="{}" NumberOfComponents="{}"{} format="appended" offset="{}"/>)",
                     a.type, xml_escape(a.name), a.components,
                     field ? fmt::format(R"( NumberOfTuples="{}")", a.tuples) : std::string{}, a.offset);
}

void check_arrays(const std::vector<DataArray>& arrays, size_t n, const char* what,
                  const std::set<std::string>& reserved) {
  std::set<std::string> names;
  for (const auto& a : arrays) {
    if (a.name.empty()) throw_usage_error(fmt::format("write_network_vtp: a {} array has no name", what));
    if (reserved.count(a.name) || !names.insert(a.name).second)
      throw_usage_error(fmt::format("write_network_vtp: {} array name '{}' is used twice (or reserved)", what, a.name));
    if (a.components < 1 || a.values.size() != n * static_cast<size_t>(a.components))
      throw_usage_error(fmt::format("write_network_vtp: {} array '{}' has {} values; expected {} x {} components", what,
                                    a.name, a.values.size(), n, a.components));
  }
}

}  // namespace

void write_network_vtp(const Network& net, const std::string& path, const std::vector<DataArray>& point_data,
                       const std::vector<DataArray>& cell_data) {
  const auto nn = static_cast<size_t>(net.num_nodes());
  const auto ns = static_cast<size_t>(net.num_segments());
  const auto nb = static_cast<size_t>(net.num_branches());
  check_arrays(point_data, nn, "point", {"radius"});
  check_arrays(cell_data, ns, "cell",
               {"radius", "radius_from", "radius_to", "length", "shape", "branch_id", "segment_id"});

  Appended data;
  std::vector<ArrayXml> field, point, cell;
  auto add = [&](std::vector<ArrayXml>& where, const std::string& name, const auto& values, int comps = 1) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    const std::string type = std::is_same_v<T, double> ? "Float64" : std::is_same_v<T, int64_t> ? "Int64" : "Int32";
    where.push_back({type, name, comps, values.size() / static_cast<size_t>(comps), data.add(values)});
  };

  // Field data: the marker and the branch structure.
  add(field, "flowire_network", std::vector<int32_t>{1});
  std::vector<int64_t> seg_off{0}, seg_ids, node_off{0}, node_ids;
  for (const auto& b : net.branches()) {
    seg_ids.insert(seg_ids.end(), b.segments.begin(), b.segments.end());
    node_ids.insert(node_ids.end(), b.nodes.begin(), b.nodes.end());
    seg_off.push_back(static_cast<int64_t>(seg_ids.size()));
    node_off.push_back(static_cast<int64_t>(node_ids.size()));
  }
  add(field, "branch_segment_offsets", seg_off);
  add(field, "branch_segments", seg_ids);
  add(field, "branch_node_offsets", node_off);
  add(field, "branch_nodes", node_ids);

  // Point data, for display only (a node has no radius of its own): the mean of the radii
  // the segments meeting at the node have there.
  std::vector<double> node_r(nn, 0.0);
  for (size_t i = 0; i < nn; ++i) {
    const auto [b, e] = net.node_segments(static_cast<int>(i));
    double sum = 0.0;
    for (const int* s = b; s != e; ++s) {
      const auto& seg = net.segment(*s);
      sum += seg.node_from == static_cast<int>(i) ? seg.radius_from : seg.radius_to;
    }
    node_r[i] = e > b ? sum / static_cast<double>(e - b) : 0.0;
  }
  add(point, "radius", node_r);
  for (const auto& a : point_data) add(point, a.name, a.values, a.components);

  std::vector<double> radius(ns), radius_from(ns), radius_to(ns), length(ns), shape(ns);
  std::vector<int32_t> branch(ns), segment_id(ns);
  std::vector<int64_t> conn(2 * ns), offsets(ns);
  for (size_t s = 0; s < ns; ++s) {
    const auto& seg = net.segment(static_cast<int>(s));
    radius[s] = seg.radius;
    radius_from[s] = seg.radius_from;
    radius_to[s] = seg.radius_to;
    length[s] = seg.length;
    shape[s] = seg.shape;
    branch[s] = seg.branch;
    segment_id[s] = static_cast<int32_t>(s);
    conn[2 * s] = seg.node_from;
    conn[2 * s + 1] = seg.node_to;
    offsets[s] = static_cast<int64_t>(2 * s + 2);
  }
  add(cell, "radius", radius);
  add(cell, "radius_from", radius_from);
  add(cell, "radius_to", radius_to);
  add(cell, "length", length);
  add(cell, "shape", shape);
  add(cell, "branch_id", branch);
  add(cell, "segment_id", segment_id);
  for (const auto& a : cell_data) add(cell, a.name, a.values, a.components);

  std::vector<double> xyz(3 * nn);
  for (size_t i = 0; i < nn; ++i)
    for (int k = 0; k < 3; ++k) xyz[3 * i + static_cast<size_t>(k)] = net.node(static_cast<int>(i))[k];
  const size_t points_offset = data.add(xyz);
  const size_t conn_offset = data.add(conn);
  const size_t offsets_offset = data.add(offsets);

  std::string x;
  x += "<?xml version=\"1.0\"?>\n";
  x += fmt::format(R"(<VTKFile type="PolyData" version="0.1" byte_order="{}" header_type="UInt64">)",
                   std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian");
  x += "\n  <PolyData>\n    <FieldData>\n";
  for (const auto& a : field) x += "      " + array_tag(a, true) + "\n";
  x += fmt::format(R"(      <Array type="String" Name="branch_names" NumberOfTuples="{}" format="ascii">)", nb);
  x += "\n       ";
  for (const auto& b : net.branches()) {
    for (const char c : b.name) x += fmt::format(" {}", static_cast<int>(static_cast<unsigned char>(c)));
    x += " 0";
  }
  x += "\n      </Array>\n    </FieldData>\n";
  x += fmt::format(
      R"(    <Piece NumberOfPoints="{}" NumberOfVerts="0" NumberOfLines="{}" NumberOfStrips="0" NumberOfPolys="0">)",
      nn, ns);
  x += "\n      <PointData Scalars=\"radius\">\n";
  for (const auto& a : point) x += "        " + array_tag(a, false) + "\n";
  x += "      </PointData>\n      <CellData Scalars=\"radius\">\n";
  for (const auto& a : cell) x += "        " + array_tag(a, false) + "\n";
  x += "      </CellData>\n      <Points>\n";
  x += fmt::format(
      R"(        <DataArray type="Float64" Name="Points" NumberOfComponents="3" format="appended" offset="{}"/>)",
      points_offset);
  x += "\n      </Points>\n      <Lines>\n";
  x += fmt::format(R"(        <DataArray type="Int64" Name="connectivity" format="appended" offset="{}"/>)",
                   conn_offset);
  x += "\n";
  x += fmt::format(R"(        <DataArray type="Int64" Name="offsets" format="appended" offset="{}"/>)", offsets_offset);
  x += "\n      </Lines>\n    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _";

  write_stream_atomically(path, [&](std::ostream& out) {
    out << x;
    out.write(data.bytes().data(), static_cast<std::streamsize>(data.bytes().size()));
    out << "\n  </AppendedData>\n</VTKFile>\n";
  });
}

void write_network_yaml(const Network& net, const std::string& path) {
  std::string y;
  y += "# flowire vessel network. Positions and radii in metres. 'branches' gives each branch's points\n";
  y += "# [x, y, z, r] (r: the branch's radius at the point); 'nodes' and 'segments'\n";
  y += "# ([from, to, radius, length, branch, radius_from, radius_to, shape]) give the exact network\n";
  y += "# (shape: the sections' Poiseuille resistance over that of circles of the same area).\n";
  y += "format: flowire-network\nversion: 1\nlength_unit: m\nbranches:\n";
  auto list = [](const std::vector<int>& v) {
    std::string s = "[";
    for (size_t k = 0; k < v.size(); ++k) s += fmt::format("{}{}", k ? ", " : "", v[k]);
    return s + "]";
  };
  for (const auto& b : net.branches()) {
    std::string quoted = "\"";
    for (const char c : b.name) {
      switch (c) {
        case '"':
          quoted += "\\\"";
          break;
        case '\\':
          quoted += "\\\\";
          break;
        case '\n':
          quoted += "\\n";
          break;
        case '\t':
          quoted += "\\t";
          break;
        default:
          if (static_cast<unsigned char>(c) < 0x20) {
            quoted += fmt::format("\\x{:02x}", static_cast<int>(c));
          } else {
            quoted += c;
          }
      }
    }
    quoted += "\"";
    y += fmt::format("  - name: {}\n    points:\n", quoted);
    for (size_t k = 0; k < b.nodes.size(); ++k) {
      double r = 0.0;
      if (k < b.segments.size())
        r = net.segment(b.segments[k]).radius_from;
      else if (k > 0 && k - 1 < b.segments.size())
        r = net.segment(b.segments[k - 1]).radius_to;
      const auto& p = net.node(b.nodes[k]);
      y += fmt::format("      - [{}, {}, {}, {}]\n", p.x(), p.y(), p.z(), r);
    }
    y += fmt::format("    nodes: {}\n    segments: {}\n", list(b.nodes), list(b.segments));
  }
  y += "nodes:\n";
  for (const auto& p : net.nodes()) y += fmt::format("  - [{}, {}, {}]\n", p.x(), p.y(), p.z());
  y += "segments:\n";
  for (const auto& s : net.segments())
    y += fmt::format("  - [{}, {}, {}, {}, {}, {}, {}, {}]\n", s.node_from, s.node_to, s.radius, s.length, s.branch,
                     s.radius_from, s.radius_to, s.shape);
  write_text_atomically(path, y);
}

void write_network(const Network& net, const std::string& path) {
  auto ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".vtp") return write_network_vtp(net, path);
  if (ext == ".yaml" || ext == ".yml") return write_network_yaml(net, path);
  throw_usage_error(fmt::format("{}: cannot write a network in this format (use .vtp or .yaml)", path));
}

}  // namespace flowire::vessels
