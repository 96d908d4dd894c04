// Legacy VTK poly data (.vtk, ASCII or BINARY), read without VTK: VTK's own legacy reader
// crashes on some corrupt files, and centerline files need only points, line cells and
// numeric point / cell / field arrays.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "flowire/common/error.hpp"
#include "polydata_internal.hpp"

namespace flowire::vessels::detail {
namespace {

std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

class Cursor {
 public:
  Cursor(std::string text, std::string path) : s_(std::move(text)), path_(std::move(path)) {}

  [[noreturn]] void fail(std::string_view what) const {
    throw_input_error(fmt::format("{}:{}", path_, line_at(pos_)), what);
  }
  [[nodiscard]] int line_at(size_t pos) const {
    return 1 + static_cast<int>(
                   std::count(s_.begin(), s_.begin() + static_cast<std::ptrdiff_t>(std::min(pos, s_.size())), '\n'));
  }
  [[nodiscard]] size_t remaining() const { return s_.size() - pos_; }
  [[nodiscard]] bool at_end() {
    skip_space();
    return pos_ >= s_.size();
  }
  std::string line() {
    const auto e = s_.find('\n', pos_);
    std::string out = s_.substr(pos_, e == std::string::npos ? std::string::npos : e - pos_);
    pos_ = e == std::string::npos ? s_.size() : e + 1;
    if (!out.empty() && out.back() == '\r') out.pop_back();
    return out;
  }
  std::string token() {
    skip_space();
    if (pos_ >= s_.size()) fail("unexpected end of file (truncated file)");
    const size_t b = pos_;
    while (pos_ < s_.size() && !std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
    return s_.substr(b, pos_ - b);
  }
  long long count(std::string_view what) {
    const auto t = token();
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(t.c_str(), &end, 10);
    if (end != t.c_str() + t.size() || errno != 0 || v < 0) fail(fmt::format("{}: '{}' is not a count", what, t));
    if (static_cast<unsigned long long>(v) > s_.size())
      fail(fmt::format("{} {} does not fit in a file of {} bytes (corrupt or truncated file)", what, v, s_.size()));
    return v;
  }
  double number() {
    const auto t = token();
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (end != t.c_str() + t.size()) fail(fmt::format("'{}' is not a number", t.substr(0, 40)));
    return v;
  }
  /// After a header line in a BINARY file the data starts on the next line.
  void to_next_line() {
    const auto e = s_.find('\n', pos_);
    pos_ = e == std::string::npos ? s_.size() : e + 1;
  }
  /// `n` big-endian values of `type`.
  std::vector<double> binary(size_t n, const std::string& type) {
    const size_t size = type_size(type);
    if (size == 0) fail(fmt::format("data type '{}' is not supported in binary files", type));
    if (n > remaining() / size)
      fail(fmt::format("{} values of {} do not fit in the rest of the file (truncated)", n, type));
    std::vector<double> out(n);
    for (size_t i = 0; i < n; ++i) {
      unsigned char b[8];
      std::memcpy(b, s_.data() + pos_ + i * size, size);
      if (std::endian::native == std::endian::little) std::reverse(b, b + size);
      out[i] = decode(b, type);
    }
    pos_ += n * size;
    return out;
  }
  /// Whether the next word is `w` (in a BINARY file: whether the next line starts with it).
  [[nodiscard]] bool next_word_is(std::string_view w, bool binary_mode) {
    size_t p = pos_;
    if (binary_mode) {
      const auto e = s_.find('\n', pos_);
      if (e == std::string::npos) return false;
      p = e + 1;
    }
    while (p < s_.size() && std::isspace(static_cast<unsigned char>(s_[p]))) ++p;
    return s_.compare(p, w.size(), w) == 0;
  }
  void skip_space() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }

 private:
  static size_t type_size(const std::string& t) {
    if (t == "char" || t == "unsigned_char" || t == "bit") return t == "bit" ? 0 : 1;
    if (t == "short" || t == "unsigned_short") return 2;
    if (t == "int" || t == "unsigned_int" || t == "float" || t == "vtkidtype") return 4;
    if (t == "long" || t == "unsigned_long" || t == "double" || t == "vtktypeint64" || t == "vtktypeuint64") return 8;
    return 0;
  }
  static double decode(const unsigned char* b, const std::string& t) {
    auto get = [&](auto v) {
      std::memcpy(&v, b, sizeof v);
      return static_cast<double>(v);
    };
    if (t == "char") return get(int8_t{});
    if (t == "unsigned_char") return get(uint8_t{});
    if (t == "short") return get(int16_t{});
    if (t == "unsigned_short") return get(uint16_t{});
    if (t == "int" || t == "vtkidtype") return get(int32_t{});
    if (t == "unsigned_int") return get(uint32_t{});
    if (t == "float") return get(float{});
    if (t == "double") return get(double{});
    if (t == "unsigned_long" || t == "vtktypeuint64") return get(uint64_t{});
    return get(int64_t{});
  }

  std::string s_;
  std::string path_;
  size_t pos_ = 0;
};

struct Reader {
  Cursor cur;
  bool binary = false;

  std::vector<double> values(size_t n, std::string type) {
    type = [&] {
      std::string t = type;
      for (auto& c : t) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return t;
    }();
    if (n > cur.remaining()) cur.fail(fmt::format("{} values do not fit in the rest of the file (truncated)", n));
    if (binary) {
      cur.to_next_line();
      return cur.binary(n, type);
    }
    std::vector<double> out(n);
    for (auto& v : out) v = cur.number();
    return out;
  }

  std::vector<long long> ids(size_t n, const std::string& type) {
    const auto v = values(n, type);
    std::vector<long long> out(n);
    for (size_t i = 0; i < n; ++i) {
      if (!(std::abs(v[i]) < 9e15) || std::floor(v[i]) != v[i])
        cur.fail(fmt::format("cell entry {} is not an index", v[i]));
      out[i] = static_cast<long long>(v[i]);
    }
    return out;
  }
};

}  // namespace

PolyData read_legacy_polydata(const std::string& path, const std::string& text) {
  Reader r{Cursor(text, path)};
  PolyData pd;
  pd.source = path;
  const auto l1 = r.cur.line();
  if (l1.rfind("# vtk DataFile", 0) != 0) throw_input_error(path, "not a legacy VTK file (no '# vtk DataFile' header)");
  (void)r.cur.line();  // title
  const auto format = upper(r.cur.line());
  if (format.rfind("ASCII", 0) == 0)
    r.binary = false;
  else if (format.rfind("BINARY", 0) == 0)
    r.binary = true;
  else
    throw_input_error(fmt::format("{}:3", path), "expected ASCII or BINARY");
  if (upper(r.cur.token()) != "DATASET") r.cur.fail("expected DATASET POLYDATA");
  const auto kind = upper(r.cur.token());
  if (kind != "POLYDATA") r.cur.fail(fmt::format("the file holds {}, not POLYDATA (centerlines are poly data)", kind));

  enum class Target { None, Point, Cell };
  Target target = Target::None;
  long long target_n = 0;
  std::vector<std::vector<long long>> lines;
  bool have_points = false;
  auto arrays = [&]() -> std::vector<NumericArray>& {
    if (target == Target::Point) return pd.point_data;
    if (target == Target::Cell) return pd.cell_data;
    r.cur.fail("attribute data before POINT_DATA or CELL_DATA");
  };
  long long verts = 0;
  while (!r.cur.at_end()) {
    const auto key = upper(r.cur.token());
    if (key == "POINTS") {
      const auto n = r.cur.count("POINTS");
      const auto v = r.values(static_cast<size_t>(3 * n), r.cur.token());
      pd.points.resize(static_cast<size_t>(n));
      for (size_t i = 0; i < pd.points.size(); ++i) pd.points[i] = Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
      have_points = true;
    } else if (key == "VERTICES" || key == "LINES" || key == "POLYGONS" || key == "TRIANGLE_STRIPS") {
      const auto n = r.cur.count(key);
      const auto size = r.cur.count(key);
      std::vector<std::vector<long long>> cells;
      // Version 5 files: OFFSETS / CONNECTIVITY blocks; older: `size` entries "count id id ...".
      if (r.cur.next_word_is("OFFSETS", r.binary)) {
        (void)r.cur.token();
        const auto off = r.ids(static_cast<size_t>(n), r.cur.token());
        if (upper(r.cur.token()) != "CONNECTIVITY") r.cur.fail("expected CONNECTIVITY after OFFSETS");
        const auto conn = r.ids(static_cast<size_t>(size), r.cur.token());
        for (size_t c = 0; c + 1 < off.size(); ++c) {
          if (off[c] < 0 || off[c + 1] < off[c] || off[c + 1] > size)
            r.cur.fail(fmt::format("{}: offset {} out of range", key, c));
          cells.emplace_back(conn.begin() + off[c], conn.begin() + off[c + 1]);
        }
      } else {
        const auto flat = r.ids(static_cast<size_t>(size), "int");
        size_t k = 0;
        for (long long c = 0; c < n; ++c) {
          if (k >= flat.size()) r.cur.fail(fmt::format("{}: fewer entries than {} cells", key, n));
          const long long m = flat[k++];
          if (m < 0 || static_cast<size_t>(m) > flat.size() - k)
            r.cur.fail(fmt::format("{}: cell {} has {} points, more than the entries left", key, c, m));
          cells.emplace_back(flat.begin() + static_cast<std::ptrdiff_t>(k),
                             flat.begin() + static_cast<std::ptrdiff_t>(k + static_cast<size_t>(m)));
          k += static_cast<size_t>(m);
        }
      }
      if (key == "LINES")
        lines.insert(lines.end(), cells.begin(), cells.end());
      else {
        pd.other_cells += static_cast<long long>(cells.size());
        if (key == "VERTICES") verts += static_cast<long long>(cells.size());
      }
    } else if (key == "POINT_DATA" || key == "CELL_DATA") {
      target = key == "POINT_DATA" ? Target::Point : Target::Cell;
      target_n = r.cur.count(key);
    } else if (key == "SCALARS") {
      NumericArray a;
      a.name = r.cur.token();
      const auto type = r.cur.token();
      // optional component count, then LOOKUP_TABLE name
      auto t = r.cur.token();
      a.components = 1;
      if (upper(t) != "LOOKUP_TABLE") {
        char* end = nullptr;
        const long c = std::strtol(t.c_str(), &end, 10);
        if (end != t.c_str() + t.size() || c < 1 || c > 4)
          r.cur.fail(fmt::format("SCALARS {}: bad component count '{}'", a.name, t));
        a.components = static_cast<int>(c);
        t = r.cur.token();
      }
      if (upper(t) != "LOOKUP_TABLE") r.cur.fail(fmt::format("SCALARS {}: expected LOOKUP_TABLE", a.name));
      (void)r.cur.token();
      auto& dest = arrays();
      a.values = r.values(static_cast<size_t>(target_n) * static_cast<size_t>(a.components), type);
      dest.push_back(std::move(a));
    } else if (key == "VECTORS" || key == "NORMALS" || key == "TENSORS") {
      NumericArray a;
      a.name = r.cur.token();
      a.components = key == "TENSORS" ? 9 : 3;
      const auto type = r.cur.token();
      auto& dest = arrays();
      a.values = r.values(static_cast<size_t>(target_n) * static_cast<size_t>(a.components), type);
      dest.push_back(std::move(a));
    } else if (key == "TEXTURE_COORDINATES") {
      NumericArray a;
      a.name = r.cur.token();
      a.components = static_cast<int>(std::clamp<long long>(r.cur.count(key), 1, 3));
      const auto type = r.cur.token();
      auto& dest = arrays();
      a.values = r.values(static_cast<size_t>(target_n) * static_cast<size_t>(a.components), type);
      dest.push_back(std::move(a));
    } else if (key == "COLOR_SCALARS") {
      NumericArray a;
      a.name = r.cur.token();
      a.components = static_cast<int>(std::clamp<long long>(r.cur.count(key), 1, 4));
      auto& dest = arrays();
      a.values = r.values(static_cast<size_t>(target_n) * static_cast<size_t>(a.components),
                          r.binary ? "unsigned_char" : "float");
      dest.push_back(std::move(a));
    } else if (key == "LOOKUP_TABLE") {
      (void)r.cur.token();
      const auto n = r.cur.count(key);
      (void)r.values(static_cast<size_t>(4 * n), r.binary ? "unsigned_char" : "float");
    } else if (key == "FIELD") {
      (void)r.cur.token();  // field name
      const auto narrays = r.cur.count("FIELD");
      for (long long k = 0; k < narrays; ++k) {
        NumericArray a;
        a.name = r.cur.token();
        if (upper(a.name) == "NULL_ARRAY") continue;
        const auto comps = r.cur.count("FIELD array components");
        const auto tuples = r.cur.count("FIELD array tuples");
        const auto type = r.cur.token();
        if (comps < 1 || comps > 1024) r.cur.fail(fmt::format("FIELD array {}: {} components", a.name, comps));
        if (type == "string" || type == "utf8_string")
          r.cur.fail(fmt::format("FIELD array {}: string arrays are not supported", a.name));
        a.components = static_cast<int>(comps);
        if (static_cast<unsigned long long>(comps) * static_cast<unsigned long long>(tuples) > r.cur.remaining())
          r.cur.fail(fmt::format("FIELD array {} does not fit in the rest of the file (truncated)", a.name));
        a.values = r.values(static_cast<size_t>(comps * tuples), type);
        if (target == Target::Point)
          pd.point_data.push_back(std::move(a));
        else if (target == Target::Cell)
          pd.cell_data.push_back(std::move(a));
        else
          pd.field_data.push_back(std::move(a));
      }
    } else if (key == "METADATA") {
      // Information keys written by VTK 9: skip up to the blank line that ends the block.
      r.cur.to_next_line();
      for (std::string l = r.cur.line(); !r.cur.at_end() && !l.empty(); l = r.cur.line()) {
      }
    } else {
      r.cur.fail(fmt::format("unknown keyword '{}'", key.substr(0, 40)));
    }
  }
  if (!have_points && lines.empty()) throw_input_error(path, "no POINTS and no LINES in the file");
  pd.lines = std::move(lines);
  // Cell data runs over vertices, then lines (polygons after): keep the lines' tuples.
  for (auto& a : pd.cell_data) {
    const auto comps = static_cast<size_t>(std::max(a.components, 1));
    const size_t begin = std::min(a.values.size(), static_cast<size_t>(verts) * comps);
    const size_t end = std::min(a.values.size(), begin + pd.lines.size() * comps);
    a.values = std::vector<double>(a.values.begin() + static_cast<std::ptrdiff_t>(begin),
                                   a.values.begin() + static_cast<std::ptrdiff_t>(end));
  }
  return pd;
}

}  // namespace flowire::vessels::detail
