#include "mesh_readers.h"

#include <meltlab/core/error.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>

#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

namespace meltlab::sim::io {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view kLimitName = "mesh_elements";

// ---- small parsing helpers ----------------------------------------------------------------

std::optional<std::int64_t> parse_int(std::string_view tok) {
  std::int64_t v = 0;
  const char* end = tok.data() + tok.size();
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  const auto r = std::from_chars(tok.data(), end, v);
  if (r.ec != std::errc() || r.ptr != end) return std::nullopt;
  return v;
}

/// A coordinate as OpenMesh's readers store it (a float, widened): the meshes read before this
/// reader existed stay bitwise the same.
std::optional<double> parse_coordinate(const std::string& tok) {
  char* end = nullptr;
  const float x = std::strtof(tok.c_str(), &end);
  if (end == tok.c_str() || *end != '\0' || !std::isfinite(x)) return std::nullopt;
  return static_cast<double>(x);
}

std::vector<std::string> tokens_of(const std::string& line) {
  std::istringstream ls(line);
  std::vector<std::string> out;
  for (std::string t; ls >> t;) out.push_back(t);
  return out;
}

/// Reads content lines (comments after '#' removed, blank lines skipped) with their numbers.
class LineReader {
 public:
  LineReader(const fs::path& file, bool strip_comments) : in_(file, std::ios::binary), strip_(strip_comments) {}
  bool next(std::string& out) {
    while (std::getline(in_, out)) {
      ++line_no_;
      if (!out.empty() && out.back() == '\r') out.pop_back();
      if (strip_) {
        const auto hash = out.find('#');
        if (hash != std::string::npos) out.erase(hash);
      }
      if (out.find_first_not_of(" \t\r") != std::string::npos) return true;
    }
    return false;
  }
  int line() const { return line_no_; }
  std::istream& stream() { return in_; }

 private:
  std::ifstream in_;
  bool strip_;
  int line_no_ = 0;
};

std::string at(const std::string& name, int line) { return fmt::format("{}:{}", name, line); }

void check_counts(const std::string& where, std::int64_t vertices, std::int64_t faces) {
  const std::int64_t limit = input_limits().mesh_elements;
  check_count(where, "vertex count", vertices, limit, kLimitName);
  check_count(where, "face count", faces, limit, kLimitName);
}

// ---- OFF ------------------------------------------------------------------------------------

struct OffMagic {
  bool ok = false;
  bool binary = false;
  bool texcoords = false, colours = false, normals = false, other_dimension = false;
};

// OpenMesh's header: [ST][C][N][4][n]OFF [BINARY]
OffMagic parse_off_magic(std::string_view first_line) {
  OffMagic m;
  std::string_view p = first_line;
  while (!p.empty() && std::isspace(static_cast<unsigned char>(p.front()))) p.remove_prefix(1);
  if (p.substr(0, 2) == "ST") m.texcoords = true, p.remove_prefix(2);
  if (!p.empty() && p.front() == 'C') m.colours = true, p.remove_prefix(1);
  if (!p.empty() && p.front() == 'N') m.normals = true, p.remove_prefix(1);
  if (!p.empty() && p.front() == '4') m.other_dimension = true, p.remove_prefix(1);
  if (!p.empty() && p.front() == 'n') m.other_dimension = true, p.remove_prefix(1);
  if (p.substr(0, 3) != "OFF") return m;
  p.remove_prefix(3);
  m.ok = p.empty() || std::isspace(static_cast<unsigned char>(p.front()));
  while (!p.empty() && std::isspace(static_cast<unsigned char>(p.front()))) p.remove_prefix(1);
  m.binary = p.substr(0, 6) == "BINARY";
  return m;
}
PolygonMesh read_off_ascii(const fs::path& file, std::int64_t file_size) {
  const std::string name = file.string();
  LineReader in(file, true);
  std::string line;
  in.next(line);  // the magic line (checked by the caller)
  std::vector<std::string> header = tokens_of(line);
  header.erase(header.begin());  // "OFF"
  int header_line = in.line();
  while (header.size() < 3 && in.next(line)) {
    header_line = in.line();
    for (auto& t : tokens_of(line)) header.push_back(t);
  }
  if (header.size() < 2)
    throw InputError(fmt::format("{}: OFF header lacks the vertex and face counts", at(name, header_line)));
  const auto v = parse_int(header[0]), f = parse_int(header[1]);
  if (!v || !f)
    throw InputError(
        fmt::format("{}: OFF counts '{}' '{}' are not whole numbers", at(name, header_line), header[0], header[1]));
  check_counts(at(name, header_line), *v, *f);
  // The smallest records: a vertex "0 0 0\n" (6 bytes), a triangle "3 0 0 0\n" (8 bytes).
  const std::int64_t need = 6 * *v + 8 * *f - 1;
  if (need > file_size)
    throw InputError(
        fmt::format("{}: truncated OFF: header declares {} vertices and {} faces, which need at least {} bytes; "
                    "the file has {}",
                    at(name, header_line), *v, *f, need, file_size));
  PolygonMesh mesh;
  mesh.V.reserve(static_cast<std::size_t>(*v));  // bounded: 6 bytes of file per vertex
  mesh.faces.reserve(static_cast<std::size_t>(*f));
  for (std::int64_t k = 0; k < *v; ++k) {
    if (!in.next(line))
      throw InputError(fmt::format("{}: truncated OFF: header declares {} vertices, the file holds {}", name, *v, k));
    const auto toks = tokens_of(line);
    if (toks.size() < 3)
      throw InputError(fmt::format("{}:line {}: vertex v{} has fewer than 3 coordinates", name, in.line(), k));
    std::array<double, 3> p{};
    for (std::size_t c = 0; c < 3; ++c) {
      const auto x = parse_coordinate(toks[c]);
      if (!x)
        throw InputError(
            fmt::format("{}:line {}: vertex v{} coordinate '{}' is not a finite number", name, in.line(), k, toks[c]));
      p[c] = *x;
    }
    mesh.V.emplace_back(p[0], p[1], p[2]);
  }
  for (std::int64_t k = 0; k < *f; ++k) {
    if (!in.next(line))
      throw InputError(fmt::format("{}: truncated OFF: header declares {} faces, the file holds {}", name, *f, k));
    const auto toks = tokens_of(line);
    const auto n = toks.empty() ? std::nullopt : parse_int(toks[0]);
    if (!n || *n < 3)
      throw InputError(fmt::format("{}:line {}: face f{} does not start with a corner count >= 3", name, in.line(), k));
    if (*n > static_cast<std::int64_t>(toks.size()) - 1)
      throw InputError(fmt::format("{}:line {}: face f{} lists fewer than {} corners", name, in.line(), k, *n));
    PolygonFace face;
    face.outer.reserve(static_cast<std::size_t>(*n));
    for (std::int64_t c = 1; c <= *n; ++c) {
      const auto idx = parse_int(toks[static_cast<std::size_t>(c)]);
      if (!idx || *idx < 0 || *idx >= *v)
        throw InputError(fmt::format("{}:line {}: face f{} corner '{}' is not a vertex index in [0, {})", name,
                                     in.line(), k, toks[static_cast<std::size_t>(c)], *v));
      face.outer.push_back(static_cast<Index>(*idx));
    }
    mesh.faces.push_back(std::move(face));
  }
  return mesh;
}

PolygonMesh read_off_binary(const fs::path& file, const OffMagic& m, std::int64_t file_size) {
  const std::string name = file.string();
  if (m.colours)
    throw InputError(
        fmt::format("{}: binary OFF with colours is not supported (convert it to ASCII OFF or PLY)", name));
  std::ifstream in(file, std::ios::binary);
  std::string header;
  std::getline(in, header);
  // OpenMesh reads binary OFF as little-endian 32-bit values.
  auto read_u32 = [&](std::uint32_t& out) {
    std::array<unsigned char, 4> b{};
    if (!in.read(reinterpret_cast<char*>(b.data()), 4)) return false;
    out = std::uint32_t(b[0]) | (std::uint32_t(b[1]) << 8) | (std::uint32_t(b[2]) << 16) | (std::uint32_t(b[3]) << 24);
    return true;
  };
  std::uint32_t v = 0, f = 0, e = 0;
  if (!read_u32(v) || !read_u32(f) || !read_u32(e))
    throw InputError(fmt::format("{}: truncated binary OFF: the counts are missing", name));
  check_counts(name, v, f);
  const std::int64_t vertex_bytes = 12 + (m.normals ? 12 : 0) + (m.texcoords ? 8 : 0);
  const std::int64_t body = file_size - static_cast<std::int64_t>(in.tellg());
  if (vertex_bytes * v + 16 * std::int64_t{f} > body)
    throw InputError(
        fmt::format("{}: truncated binary OFF: header declares {} vertices and {} faces, which need at least {} "
                    "bytes; the file holds {} after the header",
                    name, v, f, vertex_bytes * v + 16 * std::int64_t{f}, body));
  PolygonMesh mesh;
  mesh.V.reserve(v);  // bounded by the size check above
  mesh.faces.reserve(f);
  for (std::uint32_t k = 0; k < v; ++k) {
    std::array<double, 3> p{};
    for (double& x : p) {
      std::uint32_t bits = 0;
      read_u32(bits);
      x = static_cast<double>(std::bit_cast<float>(bits));
    }
    mesh.V.emplace_back(p[0], p[1], p[2]);
    in.seekg(vertex_bytes - 12, std::ios::cur);
  }
  for (std::uint32_t k = 0; k < f; ++k) {
    std::uint32_t n = 0;
    if (!read_u32(n)) throw InputError(fmt::format("{}: truncated binary OFF: face f{} is missing", name, k));
    const std::int64_t left = file_size - static_cast<std::int64_t>(in.tellg());
    if (n < 3 || 4 * std::int64_t{n} > left)
      throw InputError(
          fmt::format("{}: binary OFF face f{} declares {} corners ({} bytes are left)", name, k, n, left));
    PolygonFace face;
    face.outer.reserve(n);
    for (std::uint32_t c = 0; c < n; ++c) {
      std::uint32_t idx = 0;
      read_u32(idx);
      if (idx >= v)
        throw InputError(
            fmt::format("{}: binary OFF face f{} corner {} is not a vertex index in [0, {})", name, k, idx, v));
      face.outer.push_back(static_cast<Index>(idx));
    }
    mesh.faces.push_back(std::move(face));
  }
  return mesh;
}

PolygonMesh read_off_file(const fs::path& file, std::int64_t file_size) {
  const std::string name = file.string();
  std::string first;
  {
    LineReader in(file, true);
    if (!in.next(first)) throw InputError(fmt::format("{}: no OFF header", name));
  }
  const OffMagic m = parse_off_magic(first);
  if (!m.ok) throw InputError(fmt::format("{}: not an OFF file (the first line is not an OFF header)", name));
  if (m.other_dimension)
    throw InputError(fmt::format("{}: OFF with a vertex dimension other than 3 is not supported", name));
  return m.binary ? read_off_binary(file, m, file_size) : read_off_ascii(file, file_size);
}

// ---- PLY ------------------------------------------------------------------------------------

enum class PlyFormat { kAscii, kLittle, kBig };
enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

int ply_size(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

std::optional<PlyType> ply_type(std::string_view t) {
  if (t == "char" || t == "int8") return PlyType::kInt8;
  if (t == "uchar" || t == "uint8") return PlyType::kUint8;
  if (t == "short" || t == "int16") return PlyType::kInt16;
  if (t == "ushort" || t == "uint16") return PlyType::kUint16;
  if (t == "int" || t == "int32") return PlyType::kInt32;
  if (t == "uint" || t == "uint32") return PlyType::kUint32;
  if (t == "float" || t == "float32") return PlyType::kFloat32;
  if (t == "double" || t == "float64") return PlyType::kFloat64;
  return std::nullopt;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;   ///< the scalar, or a list's items
  std::optional<PlyType> count_type;  ///< set for lists
};
struct PlyElement {
  std::string name;
  std::int64_t count = 0;
  int line = 0;
  std::vector<PlyProperty> properties;
};

/// Values of a PLY body, ASCII tokens or binary numbers, with the end of the file checked at
/// every read.
class PlyBody {
 public:
  PlyBody(PlyFormat format, std::string bytes, std::size_t start)
      : format_(format), bytes_(std::move(bytes)), pos_(std::min(start, bytes_.size())) {}

  /// Reads one value of type t; false at the end of the data or on a malformed ASCII token.
  bool read(PlyType t, double& out) {
    if (format_ == PlyFormat::kAscii) return read_token(t, out);
    const int n = ply_size(t);
    if (pos_ + static_cast<std::size_t>(n) > bytes_.size()) return false;
    std::array<unsigned char, 8> b{};
    for (int i = 0; i < n; ++i) {
      const auto c = static_cast<unsigned char>(bytes_[pos_ + static_cast<std::size_t>(i)]);
      b[static_cast<std::size_t>(format_ == PlyFormat::kBig ? n - 1 - i : i)] = c;
    }
    pos_ += static_cast<std::size_t>(n);
    std::uint64_t u = 0;
    for (int i = n - 1; i >= 0; --i) u = (u << 8) | b[static_cast<std::size_t>(i)];
    switch (t) {
      case PlyType::kInt8:
        out = static_cast<std::int8_t>(u);
        break;
      case PlyType::kUint8:
        out = static_cast<std::uint8_t>(u);
        break;
      case PlyType::kInt16:
        out = static_cast<std::int16_t>(u);
        break;
      case PlyType::kUint16:
        out = static_cast<std::uint16_t>(u);
        break;
      case PlyType::kInt32:
        out = static_cast<std::int32_t>(u);
        break;
      case PlyType::kUint32:
        out = static_cast<std::uint32_t>(u);
        break;
      case PlyType::kFloat32:
        out = static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(u)));
        break;
      case PlyType::kFloat64:
        out = std::bit_cast<double>(u);
        break;
    }
    return true;
  }
  /// Bytes (binary) or characters (ASCII) not read yet: an upper bound on the values left.
  std::size_t left() const { return bytes_.size() - pos_; }

 private:
  bool read_token(PlyType t, double& out) {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    const std::size_t start = pos_;
    while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    if (pos_ == start) return false;
    const std::string tok = bytes_.substr(start, pos_ - start);
    if (t == PlyType::kFloat32 || t == PlyType::kFloat64) {
      char* end = nullptr;
      out =
          t == PlyType::kFloat32 ? static_cast<double>(std::strtof(tok.c_str(), &end)) : std::strtod(tok.c_str(), &end);
      return end != tok.c_str() && *end == '\0';
    }
    const auto v = parse_int(tok);
    if (!v) return false;
    out = static_cast<double>(*v);
    return true;
  }

  PlyFormat format_;
  std::string bytes_;
  std::size_t pos_;
};

/// The header of a PLY file: its format, its elements with their properties, and where the
/// body starts (bytes from the beginning of the file).
struct PlyHeader {
  PlyFormat format{};
  std::vector<PlyElement> elements;
  std::size_t body_start = 0;
};

PlyHeader read_ply_header(std::ifstream& in, const std::string& name, std::int64_t file_size) {
  std::string line;
  int line_no = 0;
  auto next_line = [&] {
    if (!std::getline(in, line)) return false;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };
  if (!next_line() || line != "ply")
    throw InputError(fmt::format("{}:1: not a PLY file (the first line is not 'ply')", name));
  std::optional<PlyFormat> format;
  std::vector<PlyElement> elements;
  constexpr int kMaxHeaderLines = 10000;
  for (bool ended = false; !ended;) {
    if (line_no > kMaxHeaderLines || !next_line())
      throw InputError(fmt::format("{}: PLY header has no 'end_header' line", name));
    const auto toks = tokens_of(line);
    const std::string where = at(name, line_no);
    if (toks.empty() || toks[0] == "comment" || toks[0] == "obj_info") continue;
    if (toks[0] == "end_header") {
      ended = true;
    } else if (toks[0] == "format") {
      if (format) throw InputError(fmt::format("{}: second PLY 'format' line", where));
      if (toks.size() != 3 || toks[2] != "1.0")
        throw InputError(fmt::format("{}: PLY 'format' line is not 'format TYPE 1.0'", where));
      if (toks[1] == "ascii")
        format = PlyFormat::kAscii;
      else if (toks[1] == "binary_little_endian")
        format = PlyFormat::kLittle;
      else if (toks[1] == "binary_big_endian")
        format = PlyFormat::kBig;
      else
        throw InputError(fmt::format("{}: unknown PLY format '{}'", where, toks[1]));
    } else if (toks[0] == "element") {
      const auto n = toks.size() == 3 ? parse_int(toks[2]) : std::nullopt;
      if (!n) throw InputError(fmt::format("{}: PLY 'element' line is not 'element NAME COUNT'", where));
      if (*n < 0) throw InputError(fmt::format("{}: element '{}' count {} is negative", where, toks[1], *n));
      if (toks[1] == "vertex") check_count(where, "vertex count", *n, input_limits().mesh_elements, kLimitName);
      if (toks[1] == "face") check_count(where, "face count", *n, input_limits().mesh_elements, kLimitName);
      // Every element instance takes at least one byte, whatever its properties.
      if (*n > file_size)
        throw InputError(fmt::format("{}: element '{}' count {} is more than a file of {} bytes can hold", where,
                                     toks[1], *n, file_size));
      for (const auto& e : elements)
        if (e.name == toks[1]) throw InputError(fmt::format("{}: element '{}' declared twice", where, toks[1]));
      elements.push_back({toks[1], *n, line_no, {}});
    } else if (toks[0] == "property") {
      if (elements.empty()) throw InputError(fmt::format("{}: PLY property before any element", where));
      PlyProperty p;
      if (toks.size() == 5 && toks[1] == "list") {
        const auto ct = ply_type(toks[2]);
        const auto it = ply_type(toks[3]);
        if (!ct || !it || *ct == PlyType::kFloat32 || *ct == PlyType::kFloat64)
          throw InputError(
              fmt::format("{}: PLY list property is not 'property list COUNT_TYPE ITEM_TYPE NAME'", where));
        p = {toks[4], *it, *ct};
      } else {
        const auto t = toks.size() == 3 ? ply_type(toks[1]) : std::nullopt;
        if (!t) throw InputError(fmt::format("{}: PLY property is not 'property TYPE NAME' with a known type", where));
        p = {toks[2], *t, std::nullopt};
      }
      elements.back().properties.push_back(p);
    } else {
      throw InputError(fmt::format("{}: unknown PLY header line '{}'", where, toks[0]));
    }
  }
  if (!format) throw InputError(fmt::format("{}: PLY header has no 'format' line", name));
  // tellg() fails (-1) when the header's last line ended the file.
  const std::streamoff header_pos = in.tellg();
  const std::size_t header_end =
      header_pos < 0 ? static_cast<std::size_t>(file_size) : static_cast<std::size_t>(header_pos);
  return {*format, std::move(elements), header_end};
}

/// The instances of one element into `mesh`: vertices (x, y, z) and faces (vertex_indices);
/// other elements and properties are read and skipped.
void read_ply_element(PlyBody& body, const PlyElement& e, std::int64_t vertex_count, const std::string& name,
                      PolygonMesh& mesh) {
  const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
  std::array<int, 3> xyz{-1, -1, -1};
  int corners = -1;
  for (std::size_t k = 0; k < e.properties.size(); ++k) {
    const auto& p = e.properties[k];
    if (is_vertex && !p.count_type && (p.name == "x" || p.name == "y" || p.name == "z"))
      xyz[static_cast<std::size_t>(p.name[0] - 'x')] = static_cast<int>(k);
    if (is_face && p.count_type && (p.name == "vertex_indices" || p.name == "vertex_index"))
      corners = static_cast<int>(k);
  }
  if (is_vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0))
    throw InputError(fmt::format("{}:{}: element 'vertex' lacks scalar properties x, y and z", name, e.line));
  if (is_face && corners < 0)
    throw InputError(fmt::format("{}:{}: element 'face' lacks the list property vertex_indices", name, e.line));
  if (is_vertex) mesh.V.reserve(static_cast<std::size_t>(e.count));  // bounded by the file size above
  if (is_face) mesh.faces.reserve(static_cast<std::size_t>(e.count));
  for (std::int64_t i = 0; i < e.count; ++i) {
    std::array<double, 3> p{};
    PolygonFace face;
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const auto& prop = e.properties[k];
      double value = 0;
      if (!prop.count_type) {
        if (!body.read(prop.type, value))
          throw InputError(fmt::format("{}: truncated or corrupt PLY: element '{}' {} property '{}' cannot be read",
                                       name, e.name, i, prop.name));
        for (std::size_t c = 0; c < 3; ++c)
          if (static_cast<int>(k) == xyz[c]) p[c] = static_cast<double>(static_cast<float>(value));
        continue;
      }
      double count = 0;
      if (!body.read(*prop.count_type, count) || count < 0)
        throw InputError(fmt::format("{}: truncated or corrupt PLY: element '{}' {} list '{}' has no valid count", name,
                                     e.name, i, prop.name));
      const auto n = static_cast<std::int64_t>(count);
      const bool is_corners = static_cast<int>(k) == corners;
      if (is_corners && n < 3) throw InputError(fmt::format("{}: PLY face {} has {} corners (at least 3)", name, i, n));
      // A list cannot hold more values than bytes (binary) or characters (ASCII) are left.
      if (static_cast<std::size_t>(n) > body.left())
        throw InputError(
            fmt::format("{}: PLY element '{}' {} lists {} values; the file ends first", name, e.name, i, n));
      if (is_corners) face.outer.reserve(static_cast<std::size_t>(n));
      for (std::int64_t j = 0; j < n; ++j) {
        if (!body.read(prop.type, value))
          throw InputError(
              fmt::format("{}: truncated or corrupt PLY: element '{}' {} list '{}' ends after {} of {} values", name,
                          e.name, i, prop.name, j, n));
        if (!is_corners) continue;
        if (!(value >= 0) || value >= static_cast<double>(vertex_count) || value != std::floor(value))
          throw InputError(
              fmt::format("{}: PLY face {} corner {} is not a vertex index in [0, {})", name, i, value, vertex_count));
        face.outer.push_back(static_cast<Index>(value));
      }
    }
    if (is_vertex) mesh.V.emplace_back(p[0], p[1], p[2]);
    if (is_face) mesh.faces.push_back(std::move(face));
  }
}

PolygonMesh read_ply_file(const fs::path& file, std::int64_t file_size) {
  const std::string name = file.string();
  std::ifstream in(file, std::ios::binary);
  const PlyHeader header = read_ply_header(in, name, file_size);
  in.clear();
  in.seekg(0);
  std::string bytes(static_cast<std::size_t>(file_size), '\0');
  in.read(bytes.data(), file_size);
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  PlyBody body(header.format, std::move(bytes), header.body_start);

  PolygonMesh mesh;
  // No 'vertex' element: no vertex, so every face corner is out of range (and a corner is
  // never converted to an index before it is checked against the count).
  std::int64_t vertex_count = 0;
  for (const auto& e : header.elements)
    if (e.name == "vertex") vertex_count = e.count;
  for (const auto& e : header.elements) read_ply_element(body, e, vertex_count, name, mesh);
  return mesh;
}

// ---- OBJ ------------------------------------------------------------------------------------

PolygonMesh read_obj_file(const fs::path& file) {
  const std::string name = file.string();
  LineReader in(file, true);
  std::string line;
  PolygonMesh mesh;
  const std::int64_t limit = input_limits().mesh_elements;
  while (in.next(line)) {
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "v") {
      std::array<double, 3> p{};
      std::string tok;
      for (std::size_t c = 0; c < 3; ++c) {
        if (!(ls >> tok))
          throw InputError(fmt::format("{}:line {}: vertex has fewer than 3 coordinates", name, in.line()));
        const auto x = parse_coordinate(tok);
        if (!x)
          throw InputError(
              fmt::format("{}:line {}: vertex coordinate '{}' is not a finite number", name, in.line(), tok));
        p[c] = *x;
      }
      if (static_cast<std::int64_t>(mesh.V.size()) >= limit)
        check_count(at(name, in.line()), "vertex count", limit + 1, limit, kLimitName);
      mesh.V.emplace_back(p[0], p[1], p[2]);
    } else if (key == "f") {
      PolygonFace face;
      for (std::string tok; ls >> tok;) {
        const auto slash = tok.find('/');
        const auto idx = parse_int(std::string_view(tok).substr(0, slash));
        const auto nv = static_cast<std::int64_t>(mesh.V.size());
        // 1-based, or negative: relative to the vertices read so far (-1 = the last one).
        const std::int64_t v = !idx ? -1 : *idx > 0 ? *idx - 1 : *idx < 0 ? nv + *idx : -1;
        if (v < 0 || v >= nv)
          throw InputError(
              fmt::format("{}:line {}: face corner '{}' is not the index of a vertex read before it (1..{})", name,
                          in.line(), tok, nv));
        face.outer.push_back(static_cast<Index>(v));
      }
      if (face.outer.size() < 3)
        throw InputError(
            fmt::format("{}:line {}: face has {} corners (at least 3)", name, in.line(), face.outer.size()));
      if (static_cast<std::int64_t>(mesh.faces.size()) >= limit)
        check_count(at(name, in.line()), "face count", limit + 1, limit, kLimitName);
      mesh.faces.push_back(std::move(face));
    }
    // vt, vn, g, o, s, usemtl, mtllib, l, ...: not part of the solid.
  }
  return mesh;
}

// ---- STL ------------------------------------------------------------------------------------

/// Corners of STL facets become vertices: equal floats are one vertex, numbered in the order
/// they first appear; facets with two equal corners are dropped (as OpenMesh's reader did).
class StlBuilder {
 public:
  explicit StlBuilder(std::string name) : name_(std::move(name)) {}
  void add_facet(const std::array<std::array<float, 3>, 3>& corners, const std::string& where) {
    std::array<Index, 3> f{};
    for (std::size_t c = 0; c < 3; ++c) {
      for (float x : corners[c])
        if (!std::isfinite(x)) throw InputError(fmt::format("{}: facet corner coordinate {} is not finite", where, x));
      const auto [it, added] = index_.try_emplace(corners[c], static_cast<Index>(mesh.V.size()));
      if (added) mesh.V.emplace_back(corners[c][0], corners[c][1], corners[c][2]);
      f[c] = it->second;
    }
    const std::int64_t limit = input_limits().mesh_elements;
    if (static_cast<std::int64_t>(mesh.faces.size()) >= limit)
      check_count(where, "facet count", limit + 1, limit, kLimitName);
    if (f[0] == f[1] || f[0] == f[2] || f[1] == f[2]) return;
    mesh.faces.push_back({{f[0], f[1], f[2]}, {}});
  }
  PolygonMesh mesh;

 private:
  std::string name_;
  std::map<std::array<float, 3>, Index> index_;
};

PolygonMesh read_stl_file(const fs::path& file, std::int64_t file_size) {
  const std::string name = file.string();
  StlBuilder out(name);
  if (file_size >= 84) {
    std::ifstream in(file, std::ios::binary);
    std::array<unsigned char, 84> head{};
    in.read(reinterpret_cast<char*>(head.data()), 84);
    const std::int64_t n = std::int64_t(head[80]) | (std::int64_t(head[81]) << 8) | (std::int64_t(head[82]) << 16) |
                           (std::int64_t(head[83]) << 24);
    if (84 + 50 * n == file_size) {
      check_count(name, "facet count", n, input_limits().mesh_elements, kLimitName);
      std::array<unsigned char, 50> rec{};
      for (std::int64_t k = 0; k < n; ++k) {
        if (!in.read(reinterpret_cast<char*>(rec.data()), 50))
          throw InputError(fmt::format("{}: truncated binary STL", name));
        std::array<std::array<float, 3>, 3> corners{};
        for (std::size_t c = 0; c < 3; ++c)
          for (std::size_t d = 0; d < 3; ++d) {
            const std::size_t o = 12 + 12 * c + 4 * d;
            corners[c][d] = std::bit_cast<float>(std::uint32_t(rec[o]) | (std::uint32_t(rec[o + 1]) << 8) |
                                                 (std::uint32_t(rec[o + 2]) << 16) | (std::uint32_t(rec[o + 3]) << 24));
          }
        out.add_facet(corners, fmt::format("{}: facet {}", name, k));
      }
      return std::move(out.mesh);
    }
  }
  // ASCII: "facet normal ..., outer loop, vertex x y z (x3), endloop, endfacet".
  LineReader in(file, false);
  std::string line;
  std::array<std::array<float, 3>, 3> corners{};
  int have = -1;  // corners of the open facet; -1 outside a facet
  while (in.next(line)) {
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "facet") {
      if (have >= 0) throw InputError(fmt::format("{}:line {}: 'facet' inside a facet", name, in.line()));
      have = 0;
    } else if (key == "vertex") {
      if (have < 0 || have >= 3)
        throw InputError(fmt::format("{}:line {}: 'vertex' outside a facet or a fourth one in it", name, in.line()));
      std::string tok;
      for (std::size_t d = 0; d < 3; ++d) {
        char* end = nullptr;
        if (!(ls >> tok))
          throw InputError(fmt::format("{}:line {}: vertex has fewer than 3 coordinates", name, in.line()));
        const float x = std::strtof(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0' || !std::isfinite(x))
          throw InputError(
              fmt::format("{}:line {}: vertex coordinate '{}' is not a finite number", name, in.line(), tok));
        corners[static_cast<std::size_t>(have)][d] = x;
      }
      ++have;
    } else if (key == "endfacet") {
      if (have != 3)
        throw InputError(
            fmt::format("{}:line {}: facet with {} vertices (3 needed)", name, in.line(), std::max(have, 0)));
      out.add_facet(corners, at(name, in.line()));
      have = -1;
    }
    // solid, outer loop, endloop, endsolid: structure only.
  }
  if (have >= 0) throw InputError(fmt::format("{}: truncated STL: the last facet has no 'endfacet'", name));
  return std::move(out.mesh);
}

}  // namespace

PolygonMesh read_off(const fs::path& file, std::int64_t file_size) { return read_off_file(file, file_size); }
PolygonMesh read_ply(const fs::path& file, std::int64_t file_size) { return read_ply_file(file, file_size); }
PolygonMesh read_obj(const fs::path& file) { return read_obj_file(file); }
PolygonMesh read_stl(const fs::path& file, std::int64_t file_size) { return read_stl_file(file, file_size); }

}  // namespace meltlab::sim::io
