#include "mesh_prescan.h"

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

bool finite_number(const std::string& tok) {
  char* end = nullptr;
  const double x = std::strtod(tok.c_str(), &end);
  return end != tok.c_str() && *end == '\0' && std::isfinite(x);
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
  if (header.size() < 2) throw InputError(fmt::format("{}: OFF header lacks the vertex and face counts", at(name, header_line)));
  const auto v = parse_int(header[0]), f = parse_int(header[1]);
  if (!v || !f)
    throw InputError(fmt::format("{}: OFF counts '{}' '{}' are not whole numbers", at(name, header_line), header[0], header[1]));
  check_counts(at(name, header_line), *v, *f);
  // The smallest records: a vertex "0 0 0\n" (6 bytes), a triangle "3 0 0 0\n" (8 bytes).
  const std::int64_t need = 6 * *v + 8 * *f - 1;
  if (need > file_size)
    throw InputError(fmt::format("{}: truncated OFF: header declares {} vertices and {} faces, which need at least {} bytes; "
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
        throw InputError(fmt::format("{}:line {}: vertex v{} coordinate '{}' is not a finite number", name, in.line(), k,
                                     toks[c]));
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
        throw InputError(fmt::format("{}:line {}: face f{} corner '{}' is not a vertex index in [0, {})", name, in.line(),
                                     k, toks[static_cast<std::size_t>(c)], *v));
      face.outer.push_back(static_cast<Index>(*idx));
    }
    mesh.faces.push_back(std::move(face));
  }
  return mesh;
}

PolygonMesh read_off_binary(const fs::path& file, const OffMagic& m, std::int64_t file_size) {
  const std::string name = file.string();
  if (m.colours)
    throw InputError(fmt::format("{}: binary OFF with colours is not supported (convert it to ASCII OFF or PLY)", name));
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
    throw InputError(fmt::format("{}: truncated binary OFF: header declares {} vertices and {} faces, which need at least {} "
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
      throw InputError(fmt::format("{}: binary OFF face f{} declares {} corners ({} bytes are left)", name, k, n, left));
    PolygonFace face;
    face.outer.reserve(n);
    for (std::uint32_t c = 0; c < n; ++c) {
      std::uint32_t idx = 0;
      read_u32(idx);
      if (idx >= v)
        throw InputError(fmt::format("{}: binary OFF face f{} corner {} is not a vertex index in [0, {})", name, k, idx, v));
      face.outer.push_back(static_cast<Index>(idx));
    }
    mesh.faces.push_back(std::move(face));
  }
  return mesh;
}

}  // namespace

PolygonMesh read_off(const fs::path& file, std::int64_t file_size) {
  const std::string name = file.string();
  std::string first;
  {
    LineReader in(file, true);
    if (!in.next(first)) throw InputError(fmt::format("{}: no OFF header", name));
  }
  const OffMagic m = parse_off_magic(first);
  if (!m.ok) throw InputError(fmt::format("{}: not an OFF file (the first line is not an OFF header)", name));
  if (m.other_dimension) throw InputError(fmt::format("{}: OFF with a vertex dimension other than 3 is not supported", name));
  return m.binary ? read_off_binary(file, m, file_size) : read_off_ascii(file, file_size);
}

namespace {

// ---- PLY ------------------------------------------------------------------------------------

enum class PlyFormat { kAscii, kLittle, kBig };

struct PlyProperty {
  int size = 0;          ///< bytes of a scalar, or of a list's items
  int count_size = 0;    ///< lists: bytes of the count (0 for scalars)
  bool count_signed = false;
};
struct PlyElement {
  std::string name;
  std::int64_t count = 0;
  int line = 0;
  std::vector<PlyProperty> properties;
};

std::optional<std::pair<int, bool>> ply_type(std::string_view t) {
  if (t == "char" || t == "int8") return std::pair{1, true};
  if (t == "uchar" || t == "uint8") return std::pair{1, false};
  if (t == "short" || t == "int16") return std::pair{2, true};
  if (t == "ushort" || t == "uint16") return std::pair{2, false};
  if (t == "int" || t == "int32") return std::pair{4, true};
  if (t == "uint" || t == "uint32") return std::pair{4, false};
  if (t == "float" || t == "float32") return std::pair{4, true};
  if (t == "double" || t == "float64") return std::pair{8, true};
  return std::nullopt;
}

DeclaredCounts prescan_ply(const fs::path& file, std::int64_t file_size) {
  const std::string name = file.string();
  std::ifstream in(file, std::ios::binary);
  std::string line;
  int line_no = 0;
  auto next_line = [&] {
    if (!std::getline(in, line)) return false;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };
  if (!next_line() || line != "ply") throw InputError(fmt::format("{}:1: not a PLY file (the first line is not 'ply')", name));
  std::optional<PlyFormat> format;
  std::vector<PlyElement> elements;
  constexpr int kMaxHeaderLines = 10000;
  bool ended = false;
  while (!ended) {
    if (line_no > kMaxHeaderLines || !next_line())
      throw InputError(fmt::format("{}: PLY header has no 'end_header' line", name));
    const auto toks = tokens_of(line);
    const std::string where = at(name, line_no);
    if (toks.empty() || toks[0] == "comment" || toks[0] == "obj_info") continue;
    if (toks[0] == "end_header") {
      ended = true;
    } else if (toks[0] == "format") {
      if (toks.size() < 2) throw InputError(fmt::format("{}: PLY 'format' line lacks the format", where));
      if (toks[1] == "ascii") format = PlyFormat::kAscii;
      else if (toks[1] == "binary_little_endian") format = PlyFormat::kLittle;
      else if (toks[1] == "binary_big_endian") format = PlyFormat::kBig;
      else throw InputError(fmt::format("{}: unknown PLY format '{}'", where, toks[1]));
    } else if (toks[0] == "element") {
      const auto n = toks.size() == 3 ? parse_int(toks[2]) : std::nullopt;
      if (!n) throw InputError(fmt::format("{}: PLY 'element' line is not 'element NAME COUNT'", where));
      if (*n < 0) throw InputError(fmt::format("{}: element '{}' count {} is negative", where, toks[1], *n));
      if (toks[1] == "vertex") check_count(where, "vertex count", *n, input_limits().mesh_elements, kLimitName);
      if (toks[1] == "face") check_count(where, "face count", *n, input_limits().mesh_elements, kLimitName);
      // Every element instance takes at least one byte, whatever its properties.
      if (*n > file_size)
        throw InputError(fmt::format("{}: element '{}' count {} is more than a file of {} bytes can hold", where, toks[1], *n,
                                     file_size));
      elements.push_back({toks[1], *n, line_no, {}});
    } else if (toks[0] == "property") {
      if (elements.empty()) throw InputError(fmt::format("{}: PLY property before any element", where));
      PlyProperty p;
      if (toks.size() >= 2 && toks[1] == "list") {
        const auto ct = toks.size() == 5 ? ply_type(toks[2]) : std::nullopt;
        const auto it = toks.size() == 5 ? ply_type(toks[3]) : std::nullopt;
        if (!ct || !it || toks[2] == "float" || toks[2] == "double" || toks[2] == "float32" || toks[2] == "float64")
          throw InputError(fmt::format("{}: PLY list property is not 'property list COUNT_TYPE ITEM_TYPE NAME'", where));
        p.count_size = ct->first;
        p.count_signed = ct->second;
        p.size = it->first;
      } else {
        const auto t = toks.size() == 3 ? ply_type(toks[1]) : std::nullopt;
        if (!t) throw InputError(fmt::format("{}: PLY property is not 'property TYPE NAME' with a known type", where));
        p.size = t->first;
      }
      elements.back().properties.push_back(p);
    } else {
      throw InputError(fmt::format("{}: unknown PLY header line '{}'", where, toks[0]));
    }
  }
  if (!format) throw InputError(fmt::format("{}: PLY header has no 'format' line", name));

  std::int64_t vertices = 0, faces = 0;
  for (const auto& e : elements) {
    if (e.name == "vertex") vertices = e.count;
    if (e.name == "face") faces = e.count;
  }

  if (*format == PlyFormat::kAscii) {
    // Values are whitespace-separated tokens; a list's count says how many tokens follow.
    auto next_token = [&](std::string& tok) { return static_cast<bool>(in >> tok); };
    std::string tok;
    for (const auto& e : elements)
      for (std::int64_t k = 0; k < e.count; ++k)
        for (const auto& p : e.properties) {
          if (!next_token(tok))
            throw InputError(fmt::format("{}: truncated PLY: element '{}' ({} declared at line {}) ends at instance {}", name,
                                         e.name, e.count, e.line, k));
          if (p.count_size == 0) continue;
          const auto n = parse_int(tok);
          if (!n || *n < 0)
            throw InputError(fmt::format("{}: PLY element '{}' {}: list count '{}' is not a whole number >= 0", name, e.name,
                                         k, tok));
          for (std::int64_t i = 0; i < *n; ++i)
            if (!next_token(tok))
              throw InputError(fmt::format("{}: truncated PLY: element '{}' {} lists {} values, the file ends first", name,
                                           e.name, k, *n));
        }
    return {vertices, faces};
  }

  const bool big = *format == PlyFormat::kBig;
  std::int64_t pos = static_cast<std::int64_t>(in.tellg());
  for (const auto& e : elements) {
    std::int64_t fixed = 0;
    bool has_list = false;
    for (const auto& p : e.properties) {
      if (p.count_size == 0) fixed += p.size;
      else has_list = true;
    }
    if (!has_list) {  // fixed-size records: arithmetic, no reading
      const std::int64_t bytes = checked_mul(fixed, e.count);
      if (bytes < 0 || pos + bytes > file_size)
        throw InputError(fmt::format("{}: truncated PLY: element '{}' ({} declared at line {}) needs {} bytes, {} are left",
                                     name, e.name, e.count, e.line, bytes, file_size - pos));
      pos += bytes;
      continue;
    }
    in.seekg(pos);
    for (std::int64_t k = 0; k < e.count; ++k)
      for (const auto& p : e.properties) {
        if (p.count_size == 0) {
          pos += p.size;
          continue;
        }
        std::array<unsigned char, 4> b{};
        in.seekg(pos);
        if (pos + p.count_size > file_size || !in.read(reinterpret_cast<char*>(b.data()), p.count_size))
          throw InputError(fmt::format("{}: truncated PLY: element '{}' ({} declared at line {}) ends at instance {}", name,
                                       e.name, e.count, e.line, k));
        std::uint32_t raw = 0;
        for (int i = 0; i < p.count_size; ++i) raw |= std::uint32_t(b[static_cast<std::size_t>(big ? p.count_size - 1 - i : i)]) << (8 * i);
        std::int64_t n = raw;
        if (p.count_signed) {
          const int bits = 8 * p.count_size;
          if (bits < 32 && (raw >> (bits - 1)) & 1u) n = static_cast<std::int64_t>(raw) - (std::int64_t{1} << bits);
          if (bits == 32) n = static_cast<std::int32_t>(raw);
        }
        pos += p.count_size;
        const std::int64_t left = file_size - pos;
        if (n < 0 || n * p.size > left)
          throw InputError(fmt::format("{}: PLY element '{}' {} lists {} values of {} bytes; {} bytes are left", name, e.name,
                                       k, n, p.size, left));
        pos += n * p.size;
      }
    if (pos > file_size)
      throw InputError(fmt::format("{}: truncated PLY: element '{}' ({} declared at line {}) runs past the end of the file",
                                   name, e.name, e.count, e.line));
  }
  return {vertices, faces};
}

// ---- OBJ and STL: no declared counts; count what is there ----------------------------------

DeclaredCounts prescan_obj(const fs::path& file) {
  const std::string name = file.string();
  LineReader in(file, false);
  std::string line;
  std::int64_t v = 0, f = 0;
  const std::int64_t limit = input_limits().mesh_elements;
  while (in.next(line)) {
    if (line.size() < 2 || (line[1] != ' ' && line[1] != '\t')) continue;
    if (line[0] == 'f') {
      if (++f > limit) check_count(at(name, in.line()), "face count", f, limit, kLimitName);
      continue;
    }
    if (line[0] != 'v') continue;
    if (++v > limit) check_count(at(name, in.line()), "vertex count", v, limit, kLimitName);
    // OpenMesh's OBJ reader skips a vertex line it cannot parse ("v nan 1 0"), which would
    // shift every later index: refuse it here, naming the line.
    std::istringstream ls(line.substr(2));
    std::string tok;
    for (int k = 0; k < 3; ++k) {
      if (!(ls >> tok)) throw InputError(fmt::format("{}:line {}: vertex has fewer than 3 coordinates", name, in.line()));
      if (!finite_number(tok))
        throw InputError(fmt::format("{}:line {}: vertex coordinate '{}' is not a finite number", name, in.line(), tok));
    }
  }
  return {};
}

DeclaredCounts prescan_stl(const fs::path& file, std::int64_t file_size) {
  const std::string name = file.string();
  const std::int64_t limit = input_limits().mesh_elements;
  // OpenMesh reads a file as binary STL exactly when its size is 84 + 50 * (count at byte 80).
  if (file_size >= 84) {
    std::ifstream in(file, std::ios::binary);
    std::array<unsigned char, 84> head{};
    in.read(reinterpret_cast<char*>(head.data()), 84);
    const std::int64_t n = std::int64_t(head[80]) | (std::int64_t(head[81]) << 8) | (std::int64_t(head[82]) << 16) |
                           (std::int64_t(head[83]) << 24);
    if (84 + 50 * n == file_size) {
      check_count(name, "facet count", n, limit, kLimitName);
      return {-1, n};
    }
  }
  // ASCII: count the facets before OpenMesh builds them.
  LineReader in(file, false);
  std::string line;
  std::int64_t facets = 0;
  while (in.next(line)) {
    const auto first = line.find_first_not_of(" \t");
    if (first != std::string::npos && line.compare(first, 5, "facet") == 0 && ++facets > limit)
      check_count(at(name, in.line()), "facet count", facets, limit, kLimitName);
  }
  return {-1, facets};
}

}  // namespace

DeclaredCounts prescan_mesh_file(const fs::path& file, const std::string& ext, std::int64_t file_size) {
  if (ext == "ply") return prescan_ply(file, file_size);
  if (ext == "obj") return prescan_obj(file);
  if (ext == "stl") return prescan_stl(file, file_size);
  return {};
}

}  // namespace meltlab::sim::io
