// NRRD volumes, the subset medical users have (see volume/nrrd_file.h).

#include <meltlab/render/volume/nrrd_file.h>

#include <meltlab/core/text_fields.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <vector>

namespace meltlab::render {

namespace fs = std::filesystem;

/// The longest header meltlab reads (a real header is a few hundred bytes).
constexpr std::int64_t kNrrdMaxHeaderBytes = 1 << 20;

std::int64_t NrrdHeader::sample_bytes() const {
  return checked_mul(checked_mul(checked_mul(dims[0], dims[1]), dims[2]), scalar_bytes(type));
}

namespace {

std::optional<ScalarType> nrrd_type(const std::string& t) {
  static const std::map<std::string, ScalarType> kTypes = {
      {"signed char", ScalarType::kInt8},
      {"int8", ScalarType::kInt8},
      {"int8_t", ScalarType::kInt8},
      {"uchar", ScalarType::kUint8},
      {"unsigned char", ScalarType::kUint8},
      {"uint8", ScalarType::kUint8},
      {"uint8_t", ScalarType::kUint8},
      {"short", ScalarType::kInt16},
      {"short int", ScalarType::kInt16},
      {"signed short", ScalarType::kInt16},
      {"signed short int", ScalarType::kInt16},
      {"int16", ScalarType::kInt16},
      {"int16_t", ScalarType::kInt16},
      {"ushort", ScalarType::kUint16},
      {"unsigned short", ScalarType::kUint16},
      {"unsigned short int", ScalarType::kUint16},
      {"uint16", ScalarType::kUint16},
      {"uint16_t", ScalarType::kUint16},
      {"int", ScalarType::kInt32},
      {"signed int", ScalarType::kInt32},
      {"int32", ScalarType::kInt32},
      {"int32_t", ScalarType::kInt32},
      {"uint", ScalarType::kUint32},
      {"unsigned int", ScalarType::kUint32},
      {"uint32", ScalarType::kUint32},
      {"uint32_t", ScalarType::kUint32},
      {"float", ScalarType::kFloat32},
      {"double", ScalarType::kFloat64},
  };
  const auto it = kTypes.find(t);
  if (it == kTypes.end()) return std::nullopt;
  return it->second;
}

/// "(a,b,c)" → three finite numbers; nullopt otherwise.
std::optional<Eigen::Vector3d> vector_of(const std::string& s) {
  if (s.size() < 2 || s.front() != '(' || s.back() != ')') return std::nullopt;
  const std::string inner = s.substr(1, s.size() - 2);
  Eigen::Vector3d v;
  std::size_t start = 0;
  for (int a = 0; a < 3; ++a) {
    const std::size_t comma = inner.find(',', start);
    if ((a < 2) != (comma != std::string::npos)) return std::nullopt;
    const auto x =
        parse_finite(trim_blanks(inner.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (!x) return std::nullopt;
    v[a] = *x;
    start = comma + 1;
  }
  return v;
}

/// The vectors of "(a,b,c) (d,e,f) (g,h,i)" (spaces inside the parentheses allowed).
std::vector<std::string> vectors_in(const std::string& s) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    if (i == s.size()) break;
    std::size_t j = i;
    if (s[i] == '(') {
      j = s.find(')', i);
      j = j == std::string::npos ? s.size() : j + 1;
    } else {
      while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    }
    std::string v = s.substr(i, j - i);
    v.erase(std::remove_if(v.begin(), v.end(), [](char c) { return c == ' ' || c == '\t'; }), v.end());
    out.push_back(v);
    i = j;
  }
  return out;
}

const std::set<std::string>& informative_fields() {
  static const std::set<std::string> k = {"content",           "kinds",    "labels",       "units",       "space units",
                                          "measurement frame", "min",      "max",          "old min",     "oldmin",
                                          "old max",           "oldmax",   "thicknesses",  "axis mins",   "axismins",
                                          "axis maxs",         "axismaxs", "sample units", "sampleunits", "space",
                                          "space dimension",   "number"};
  return k;
}

}  // namespace

NrrdHeader parse_nrrd_header(std::string_view text, const std::string& what, const fs::path& base_dir) {
  NrrdHeader h;
  std::size_t pos = 0;
  int line_no = 0;
  bool ended = false;
  std::set<std::string> seen;
  bool have_type = false, have_dimension = false, have_sizes = false, have_endian = false, have_encoding = false,
       have_spacing = false;
  std::string spacing_field;
  while (pos < text.size()) {
    if (pos > std::size_t(kNrrdMaxHeaderBytes))
      throw InputError(fmt::format("{}:{}: the header is longer than {} bytes", what, line_no, kNrrdMaxHeaderBytes));
    const std::size_t lf = text.find('\n', pos);
    const std::size_t end = lf == std::string_view::npos ? text.size() : lf;
    const std::string line = trim_blanks(text.substr(pos, end - pos));
    pos = lf == std::string_view::npos ? text.size() : lf + 1;
    ++line_no;
    auto fail = [&](const std::string& problem) { throw InputError(fmt::format("{}:{}: {}", what, line_no, problem)); };
    if (line_no == 1) {
      if (line.size() != 8 || line.rfind("NRRD000", 0) != 0 || line[7] < '1' || line[7] > '5')
        fail(fmt::format("not a NRRD file (the first line is '{}', not NRRD0001..NRRD0005)",
                         line.substr(0, std::min<std::size_t>(line.size(), 40))));
      h.version = line[7] - '0';
      continue;
    }
    for (char c : line)
      if (static_cast<unsigned char>(c) < 0x20 && c != '\t')
        fail("a control byte in the header (binary data before the empty line that ends the header?)");
    if (line.empty()) {
      ended = true;
      break;
    }
    if (line[0] == '#') continue;
    const std::size_t colon = line.find(": ");
    const std::size_t kv = line.find(":=");
    if (kv != std::string::npos && (colon == std::string::npos || kv < colon)) continue;  // key/value pair
    if (colon == std::string::npos) fail(fmt::format("'{}' is not a 'field: value' line", line.substr(0, 60)));
    const std::string field = line.substr(0, colon), value = trim_blanks(line.substr(colon + 2));
    if (!seen.insert(field).second) fail(fmt::format("field '{}' given twice", field));
    const auto w = blank_separated_fields(value);
    if (field == "type") {
      const auto t = nrrd_type(value);
      if (!t) {
        if (value == "longlong" || value == "long long" || value == "int64" || value == "int64_t" ||
            value == "ulonglong" || value == "unsigned long long" || value == "uint64" || value == "uint64_t")
          fail(fmt::format("type '{}': 64-bit integer samples are not supported", value));
        fail(fmt::format("unknown type '{}' (int8..int32, uint8..uint32, float, double)", value));
      }
      h.type = *t;
      have_type = true;
    } else if (field == "dimension") {
      if (value != "3") fail(fmt::format("dimension {}: meltlab reads 3-dimensional scalar volumes only", value));
      have_dimension = true;
    } else if (field == "sizes") {
      if (w.size() != 3) fail(fmt::format("sizes '{}': three whole numbers expected", value));
      for (int a = 0; a < 3; ++a) {
        const auto x = parse_whole(w[std::size_t(a)], 1, 2147483647);
        if (!x) fail(fmt::format("size '{}' is not a whole number in [1, 2^31 - 1]", w[std::size_t(a)]));
        h.dims[std::size_t(a)] = int(*x);
      }
      const std::int64_t count = checked_mul(checked_mul(h.dims[0], h.dims[1]), h.dims[2]);
      if (count < 0) fail(fmt::format("the sample count {} x {} x {} overflows", h.dims[0], h.dims[1], h.dims[2]));
      check_count(fmt::format("{}:{}", what, line_no), "volume samples", count, input_limits().volume_samples,
                  "volume_samples");
      have_sizes = true;
    } else if (field == "endian") {
      if (value != "little" && value != "big") fail(fmt::format("unknown endian '{}' (little or big)", value));
      h.endian = value == "big" ? std::endian::big : std::endian::little;
      have_endian = true;
    } else if (field == "encoding") {
      if (value == "raw") {
        h.encoding = NrrdEncoding::kRaw;
      } else if (value == "gzip" || value == "gz") {
        h.encoding = NrrdEncoding::kGzip;
      } else if (value == "ascii" || value == "text" || value == "txt" || value == "hex" || value == "bzip2" ||
                 value == "bz2") {
        fail(fmt::format("encoding '{}' is not supported (raw or gzip; convert with teem's unu save -e raw)", value));
      } else {
        fail(fmt::format("unknown encoding '{}'", value));
      }
      have_encoding = true;
    } else if (field == "spacings") {
      if (have_spacing) fail("give 'spacings' or 'space directions', not both");
      if (w.size() != 3) fail(fmt::format("spacings '{}': three numbers expected", value));
      for (int a = 0; a < 3; ++a) {
        const auto x = parse_finite(w[std::size_t(a)]);
        if (!x || !(*x > 0)) fail(fmt::format("spacing '{}' is not a finite number > 0", w[std::size_t(a)]));
        h.spacing[a] = *x;
      }
      have_spacing = true;
    } else if (field == "space directions") {
      if (have_spacing) fail("give 'spacings' or 'space directions', not both");
      const auto vs = vectors_in(value);
      if (vs.size() != 3) fail(fmt::format("space directions '{}': three vectors (a,b,c) expected", value));
      for (int a = 0; a < 3; ++a) {
        const auto v = vector_of(vs[std::size_t(a)]);
        if (!v) fail(fmt::format("space direction '{}' is not a vector (a,b,c) of finite numbers", vs[std::size_t(a)]));
        for (int b = 0; b < 3; ++b)
          if (b != a && (*v)[b] != 0)
            fail(
                fmt::format("space direction {} is oblique or permutes the axes; meltlab reads axis-aligned volumes "
                            "only (resample it, e.g. with 3D Slicer)",
                            vs[std::size_t(a)]));
        if (!((*v)[a] != 0)) fail(fmt::format("space direction {} has length 0", vs[std::size_t(a)]));
        h.spacing[a] = std::abs((*v)[a]);
        h.mirrored[std::size_t(a)] = (*v)[a] < 0;
      }
      have_spacing = true;
    } else if (field == "space origin") {
      const auto v = vector_of(trim_blanks(value));
      if (!v) fail(fmt::format("space origin '{}' is not a vector (x,y,z) of finite numbers", value));
      h.origin = *v;
    } else if (field == "centers" || field == "centerings") {
      if (w.size() != 3) fail(fmt::format("{} '{}': three of cell | node expected", field, value));
      for (const auto& c : w)
        if (c != w[0] || (c != "cell" && c != "node" && c != "???"))
          fail(fmt::format("{} '{}': all three cell or all three node", field, value));
      h.placement = w[0] == "cell" ? SamplePlacement::kCellCentred : SamplePlacement::kNodes;
    } else if (field == "data file" || field == "datafile") {
      if (w.size() != 1 || value == "LIST" || value.find('%') != std::string::npos)
        fail(fmt::format("data file '{}': meltlab reads one detached data file (no LIST or file patterns)", value));
      const fs::path p(value);
      h.data_file = p.is_absolute() ? p : base_dir / p;
    } else if (field == "byte skip" || field == "byteskip") {
      const auto x = parse_whole(value, -1, std::int64_t(1) << 40);
      if (!x) fail(fmt::format("byte skip '{}' is not -1 or a whole number >= 0", value));
      h.byte_skip = *x;
    } else if (field == "line skip" || field == "lineskip") {
      const auto x = parse_whole(value, 0, 1 << 20);
      if (!x) fail(fmt::format("line skip '{}' is not a whole number in [0, 2^20]", value));
      h.line_skip = *x;
    } else if (field == "block size" || field == "blocksize") {
      fail("type block is not supported");
    } else if (!informative_fields().count(field)) {
      fail(fmt::format("unknown field '{}'", field.substr(0, 60)));
    }
  }
  if (line_no == 0) throw InputError(fmt::format("{}:1: empty file (not a NRRD file)", what));
  auto missing = [&](const char* field) {
    throw InputError(fmt::format("{}:{}: the header has no '{}' field", what, line_no, field));
  };
  if (!have_type) missing("type");
  if (!have_dimension) missing("dimension");
  if (!have_sizes) missing("sizes");
  if (!have_encoding) missing("encoding");
  if (!have_endian && scalar_bytes(h.type) > 1) missing("endian");
  if (h.data_file.empty() && !ended)
    throw InputError(fmt::format("{}:{}: the header has neither a 'data file' nor an empty line followed by the data",
                                 what, line_no));
  if (h.byte_skip == -1 && h.encoding != NrrdEncoding::kRaw)
    throw InputError(fmt::format("{}: byte skip -1 needs the raw encoding", what));
  if (h.sample_bytes() < 0) throw InputError(fmt::format("{}: the byte count of the samples overflows", what));
  h.header_bytes = std::int64_t(pos);
  return h;
}

namespace {

/// Inflates gzip (or zlib) data into exactly `out.size()` bytes; more or fewer is an error.
void inflate_exactly(const std::vector<std::uint8_t>& in, std::vector<std::uint8_t>& out, const std::string& what) {
  z_stream zs{};
  if (inflateInit2(&zs, 15 + 32) != Z_OK) throw InputError(fmt::format("{}: zlib could not start", what));
  constexpr std::size_t kChunk = std::size_t(1) << 30;  // z_stream counts are 32-bit
  std::size_t in_pos = 0, out_pos = 0;
  std::uint8_t extra = 0;
  bool overflow = false;
  int rc = Z_OK;
  while (rc != Z_STREAM_END) {
    if (zs.avail_in == 0 && in_pos < in.size()) {
      const std::size_t n = std::min(kChunk, in.size() - in_pos);
      zs.next_in = const_cast<Bytef*>(in.data() + in_pos);
      zs.avail_in = uInt(n);
      in_pos += n;
    }
    if (zs.avail_out == 0) {
      if (out_pos < out.size()) {
        const std::size_t n = std::min(kChunk, out.size() - out_pos);
        zs.next_out = out.data() + out_pos;
        zs.avail_out = uInt(n);
        out_pos += n;
      } else {
        zs.next_out = &extra;  // one byte beyond the declared count: detects longer data
        zs.avail_out = 1;
        overflow = true;
      }
    }
    rc = inflate(&zs, Z_NO_FLUSH);
    if (overflow && zs.avail_out == 0) {
      inflateEnd(&zs);
      throw InputError(fmt::format("{}: the gzip data inflate to more than the header's {} bytes", what, out.size()));
    }
    if (rc == Z_BUF_ERROR && zs.avail_in == 0 && in_pos == in.size()) break;  // input ended early
    if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR) {
      const std::string msg = zs.msg ? zs.msg : "corrupt data";
      inflateEnd(&zs);
      throw InputError(fmt::format("{}: the gzip data are corrupt ({})", what, msg));
    }
  }
  const std::uint64_t total = zs.total_out;
  inflateEnd(&zs);
  if (rc != Z_STREAM_END || total != out.size())
    throw InputError(
        fmt::format("{}: the gzip data inflate to {} bytes, but the header declares {}", what, total, out.size()));
}

}  // namespace

ScalarVolume read_nrrd(const fs::path& file, NrrdHeader* header_out) {
  const std::int64_t size = check_input_file(file, "volume (NRRD)");
  std::string head(std::size_t(std::min<std::int64_t>(size, kNrrdMaxHeaderBytes + 1)), '\0');
  {
    std::ifstream in(file, std::ios::binary);
    in.read(head.data(), std::streamsize(head.size()));
    if (in.gcount() != std::streamsize(head.size()))
      throw InputError(fmt::format("{}: cannot read the header", file.string()));
  }
  const NrrdHeader h = parse_nrrd_header(head, file.string(), file.parent_path());
  const bool detached = !h.data_file.empty();
  const fs::path data_path = detached ? h.data_file : file;
  const std::string data_name = data_path.string();
  const std::int64_t data_size = detached ? check_input_file(data_path, "NRRD data file") : size;
  std::int64_t start = detached ? 0 : h.header_bytes;
  std::ifstream in(data_path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open the data file", data_name));
  in.seekg(start);
  for (std::int64_t l = 0; l < h.line_skip; ++l) {
    std::string skipped;
    if (!std::getline(in, skipped) || skipped.size() > std::size_t(kNrrdMaxHeaderBytes))
      throw InputError(fmt::format("{}: cannot skip {} lines (line skip) before the data", data_name, h.line_skip));
    start += std::int64_t(skipped.size()) + 1;
  }
  const std::int64_t expected = h.sample_bytes();
  if (h.byte_skip == -1)
    start = data_size - expected;
  else
    start += h.byte_skip;
  if (start < 0 || start > data_size)
    throw InputError(fmt::format("{}: {} bytes, too short for the header's skips and {} bytes of samples", data_name,
                                 data_size, expected));
  const std::int64_t available = data_size - start;
  ScalarVolume v;
  if (h.encoding == NrrdEncoding::kRaw) {
    if (available != expected)
      throw InputError(fmt::format("{}: holds {} bytes of samples, but {} x {} x {} {} samples are {} bytes", data_name,
                                   available, h.dims[0], h.dims[1], h.dims[2], scalar_type_name(h.type), expected));
    v = ScalarVolume::allocate(h.dims, h.type, file.string());
    in.clear();
    in.seekg(start);
    in.read(reinterpret_cast<char*>(v.bytes.data()), std::streamsize(expected));
    if (in.gcount() != std::streamsize(expected)) throw InputError(fmt::format("{}: read error", data_name));
  } else {
    // A gzip stream cannot be longer than ~1032x its compressed size (deflate's limit): refuse a
    // header that declares more before allocating.
    if (expected > checked_mul(available, 1032) + 64)
      throw InputError(fmt::format("{}: {} compressed bytes cannot hold the header's {} bytes of samples", data_name,
                                   available, expected));
    std::vector<std::uint8_t> packed(static_cast<std::size_t>(available));
    in.clear();
    in.seekg(start);
    in.read(reinterpret_cast<char*>(packed.data()), std::streamsize(available));
    if (in.gcount() != std::streamsize(available)) throw InputError(fmt::format("{}: read error", data_name));
    v = ScalarVolume::allocate(h.dims, h.type, file.string());
    inflate_exactly(packed, v.bytes, data_name);
  }
  if (h.endian != std::endian::native) swap_sample_bytes(v.bytes, h.type);
  check_finite_samples(v, data_name);
  v.spacing = h.spacing;
  v.origin = h.origin;
  if (h.mirrored[0] || h.mirrored[1] || h.mirrored[2])
    spdlog::info("{}: mirrored axes in 'space directions' ({}{}{}) are not applied: the volume is read as stored",
                 file.string(), h.mirrored[0] ? "x" : "", h.mirrored[1] ? "y" : "", h.mirrored[2] ? "z" : "");
  if (header_out) *header_out = h;
  return v;
}

namespace {

std::vector<std::uint8_t> gzip_of(const std::vector<std::uint8_t>& in, const std::string& what) {
  z_stream zs{};
  if (deflateInit2(&zs, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw InputError(fmt::format("{}: zlib could not start", what));
  std::vector<std::uint8_t> out(deflateBound(&zs, uLong(in.size())) + 64);
  zs.next_in = const_cast<Bytef*>(in.data());
  zs.avail_in = uInt(in.size());
  zs.next_out = out.data();
  zs.avail_out = uInt(out.size());
  const int rc = deflate(&zs, Z_FINISH);
  const std::size_t n = zs.total_out;
  deflateEnd(&zs);
  if (rc != Z_STREAM_END) throw InputError(fmt::format("{}: gzip compression failed", what));
  out.resize(n);
  return out;
}

void write_bytes(const fs::path& file, const std::string& text, const std::vector<std::uint8_t>& data) {
  write_atomically(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw InputError(fmt::format("{}: cannot create the file", file.string()));
    out.write(text.data(), std::streamsize(text.size()));
    out.write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
    out.flush();
    if (!out) throw InputError(fmt::format("{}: write error (disk full?)", file.string()));
  });
}

}  // namespace

void write_nrrd(const fs::path& file, const ScalarVolume& v, const NrrdWriteOptions& o) {
  const std::string ext = file.extension().string();
  if (ext != ".nrrd" && ext != ".nhdr")
    throw InputError(fmt::format("{}: name a NRRD file NAME.nrrd (attached) or NAME.nhdr (detached)", file.string()));
  if (o.encoding == NrrdEncoding::kGzip && v.bytes.size() >= (std::size_t(1) << 32))
    throw InputError(fmt::format("{}: gzip writing is limited to 4 GiB of samples (use raw)", file.string()));
  std::vector<std::uint8_t> data = v.bytes;
  if (o.endian != std::endian::native) swap_sample_bytes(data, v.type);
  if (o.encoding == NrrdEncoding::kGzip) data = gzip_of(data, file.string());
  std::string h = fmt::format(
      "NRRD0004\n# written by meltlab\ntype: {}\ndimension: 3\nspace dimension: 3\nsizes: {} {} {}\n"
      "space directions: ({:.17g},0,0) (0,{:.17g},0) (0,0,{:.17g})\nspace origin: ({:.17g},{:.17g},{:.17g})\n"
      "endian: {}\nencoding: {}\n",
      scalar_type_name(v.type), v.dims[0], v.dims[1], v.dims[2], v.spacing.x(), v.spacing.y(), v.spacing.z(),
      v.origin.x(), v.origin.y(), v.origin.z(), o.endian == std::endian::big ? "big" : "little",
      o.encoding == NrrdEncoding::kGzip ? "gzip" : "raw");
  if (ext == ".nrrd") {
    write_bytes(file, h + "\n", data);
    return;
  }
  fs::path raw = file;
  raw.replace_extension(o.encoding == NrrdEncoding::kGzip ? ".raw.gz" : ".raw");
  write_bytes(raw, "", data);
  write_text_atomically(file, h + fmt::format("data file: {}\n", raw.filename().string()));
}

}  // namespace meltlab::render
