// Seed 003's VLB volume file (see volume/vlb_file.h).

#include <meltlab/render/volume/vlb_file.h>

#include <meltlab/core/text_fields.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <vector>

namespace meltlab::render {

namespace fs = std::filesystem;

std::int64_t VlbHeader::sample_bytes() const {
  return checked_mul(checked_mul(checked_mul(dims[0], dims[1]), dims[2]), scalar_bytes(type));
}

namespace {

std::string list_of_types() { return "int8, int16, int32, uint8, uint16, uint32, float or double"; }

}  // namespace

VlbHeader parse_vlb_header(std::string_view text, const std::string& what) {
  VlbHeader h;
  std::array<std::string_view, 7> lines;
  std::size_t pos = 0;
  for (int n = 0; n < 7; ++n) {
    const std::size_t limit = std::min(text.size(), pos + std::size_t(kVlbMaxLineBytes) + 2);
    const std::size_t lf = text.substr(0, limit).find('\n', pos);
    if (lf == std::string_view::npos) {
      if (limit == text.size())
        throw InputError(
            fmt::format("{}:{}: the header ends before line {} (a VLB header has 7 lines, each ending "
                        "with a line feed)",
                        what, n + 1, n + 1));
      throw InputError(
          fmt::format("{}:{}: line longer than {} bytes (not a VLB header?)", what, n + 1, kVlbMaxLineBytes));
    }
    std::string_view line = text.substr(pos, lf - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.size() > std::size_t(kVlbMaxLineBytes))
      throw InputError(
          fmt::format("{}:{}: line longer than {} bytes (not a VLB header?)", what, n + 1, kVlbMaxLineBytes));
    for (char c : line)
      if (static_cast<unsigned char>(c) < 0x20 && c != '\t')
        throw InputError(
            fmt::format("{}:{}: a control byte in the header (not a VLB header, or a line missing?)", what, n + 1));
    lines[std::size_t(n)] = line;
    pos = lf + 1;
  }
  h.header_bytes = std::int64_t(pos);
  auto fields = [&](int n, std::size_t count, const char* meaning) {
    auto f = blank_separated_fields(lines[std::size_t(n - 1)]);
    if (f.size() != count)
      throw InputError(fmt::format("{}:{}: expected {} ({} field{}), found '{}'", what, n, meaning, count,
                                   count == 1 ? "" : "s", lines[std::size_t(n - 1)]));
    return f;
  };
  // 1: version
  const auto v = fields(1, 1, "the format version VLB.1");
  if (v[0].rfind("VLB", 0) != 0)
    throw InputError(fmt::format("{}:1: not a VLB file (the first line is '{}', not VLB.1)", what, v[0]));
  if (v[0] != "VLB.1")
    throw InputError(fmt::format("{}:1: unsupported version '{}' (this meltlab reads VLB.1)", what, v[0]));
  h.version = v[0];
  // 2: dimensions
  const auto d = fields(2, 3, "the dimensions N_x N_y N_z");
  for (int a = 0; a < 3; ++a) {
    const std::int64_t x = parse_whole(d[std::size_t(a)], 1, 2147483647).value_or(-1);
    if (x < 0)
      throw InputError(
          fmt::format("{}:2: dimension '{}' is not a whole number in [1, 2^31 - 1]", what, d[std::size_t(a)]));
    h.dims[std::size_t(a)] = int(x);
  }
  const std::int64_t count = checked_mul(checked_mul(h.dims[0], h.dims[1]), h.dims[2]);
  if (count < 0)
    throw InputError(
        fmt::format("{}:2: the sample count {} x {} x {} overflows", what, h.dims[0], h.dims[1], h.dims[2]));
  check_count(fmt::format("{}:2", what), "volume samples", count, input_limits().volume_samples, "volume_samples");
  // 3: type
  const auto t = fields(3, 1, "the sample type");
  const auto type = parse_scalar_type(t[0]);
  if (!type) throw InputError(fmt::format("{}:3: unknown sample type '{}' ({})", what, t[0], list_of_types()));
  h.type = *type;
  if (h.sample_bytes() < 0)
    throw InputError(fmt::format("{}:2: the byte count of {} x {} x {} {} samples overflows", what, h.dims[0],
                                 h.dims[1], h.dims[2], t[0]));
  // 4: endianness
  const auto e = fields(4, 1, "the endianness");
  if (e[0] != "little" && e[0] != "big")
    throw InputError(fmt::format("{}:4: unknown endianness '{}' (little or big)", what, e[0]));
  h.endian = e[0] == "big" ? std::endian::big : std::endian::little;
  // 5: spacing
  const auto s = fields(5, 3, "the voxel spacing per axis");
  for (int a = 0; a < 3; ++a) {
    const auto x = parse_finite(s[std::size_t(a)]);
    if (!x || !(*x > 0))
      throw InputError(fmt::format("{}:5: spacing '{}' is not a finite number > 0", what, s[std::size_t(a)]));
    h.spacing[a] = *x;
  }
  // 6: range
  const auto r = fields(6, 2, "the minimum and maximum value");
  const auto lo = parse_finite(r[0]), hi = parse_finite(r[1]);
  if (!lo || !hi) throw InputError(fmt::format("{}:6: the range '{} {}' is not two finite numbers", what, r[0], r[1]));
  if (*lo > *hi) throw InputError(fmt::format("{}:6: the minimum {} is greater than the maximum {}", what, r[0], r[1]));
  h.min = *lo;
  h.max = *hi;
  // 7: window
  const auto w = fields(7, 2, "the recommended window");
  const auto wlo = parse_finite(w[0]), whi = parse_finite(w[1]);
  if (!wlo || !whi)
    throw InputError(fmt::format("{}:7: the window '{} {}' is not two finite numbers", what, w[0], w[1]));
  if (!(*wlo < *whi))
    throw InputError(
        fmt::format("{}:7: the window's lower bound {} is not below its upper bound {}", what, w[0], w[1]));
  h.window_lo = *wlo;
  h.window_hi = *whi;
  return h;
}

std::string format_vlb_header(const VlbHeader& h) {
  return fmt::format("{}\n{} {} {}\n{}\n{}\n{:.17g} {:.17g} {:.17g}\n{:.17g} {:.17g}\n{:.17g} {:.17g}\n", h.version,
                     h.dims[0], h.dims[1], h.dims[2], scalar_type_name(h.type),
                     h.endian == std::endian::big ? "big" : "little", h.spacing.x(), h.spacing.y(), h.spacing.z(),
                     h.min, h.max, h.window_lo, h.window_hi);
}

namespace {

/// The header of an open file, checked against the file's size.
VlbHeader header_of(const fs::path& file, std::int64_t size) {
  std::string head(std::size_t(std::min<std::int64_t>(size, 7 * (kVlbMaxLineBytes + 2))), '\0');
  std::ifstream in(file, std::ios::binary);
  in.read(head.data(), std::streamsize(head.size()));
  if (in.gcount() != std::streamsize(head.size()))
    throw InputError(fmt::format("{}: cannot read the header", file.string()));
  const VlbHeader h = parse_vlb_header(head, file.string());
  const std::int64_t data = size - h.header_bytes;
  if (data != h.sample_bytes())
    throw InputError(
        fmt::format("{}:2: the file holds {} bytes of samples after its 7-line header, but {} x {} x {} {} "
                    "samples are {} bytes",
                    file.string(), data, h.dims[0], h.dims[1], h.dims[2], scalar_type_name(h.type), h.sample_bytes()));
  return h;
}

}  // namespace

VlbHeader read_vlb_header(const fs::path& file) { return header_of(file, check_input_file(file, "volume (.vlb)")); }

VlbFile read_vlb(const fs::path& file) {
  VlbFile f;
  f.header = read_vlb_header(file);
  const VlbHeader& h = f.header;
  f.volume = ScalarVolume::allocate(h.dims, h.type, file.string());
  f.volume.spacing = h.spacing;
  std::ifstream in(file, std::ios::binary);
  in.seekg(h.header_bytes);
  in.read(reinterpret_cast<char*>(f.volume.bytes.data()), std::streamsize(f.volume.bytes.size()));
  if (in.gcount() != std::streamsize(f.volume.bytes.size()))
    throw InputError(fmt::format("{}: read error (the file changed while it was read?)", file.string()));
  if (h.endian != std::endian::native) swap_sample_bytes(f.volume.bytes, h.type);
  check_finite_samples(f.volume, file.string());
  return f;
}

void write_vlb(const fs::path& file, const ScalarVolume& v, const VlbWriteOptions& o) {
  VlbHeader h;
  h.dims = v.dims;
  h.type = v.type;
  h.endian = o.endian;
  h.spacing = v.spacing;
  const auto range = o.range ? *o.range : v.scanned_range();
  h.min = range[0];
  h.max = range[1];
  h.window_lo = o.window[0];
  h.window_hi = o.window[1];
  if (std::int64_t(v.bytes.size()) != v.sample_count() * scalar_bytes(v.type))
    throw InvariantError("write_vlb: the sample buffer does not match the dimensions");
  const std::string header = format_vlb_header(h);
  // Check that what we write reads back (a bad window or range is refused before writing).
  (void)parse_vlb_header(header, file.string());
  std::vector<std::uint8_t> swapped;
  const std::vector<std::uint8_t>* data = &v.bytes;
  if (o.endian != std::endian::native) {
    swapped = v.bytes;
    swap_sample_bytes(swapped, v.type);
    data = &swapped;
  }
  write_atomically(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw InputError(fmt::format("{}: cannot create the file", file.string()));
    out.write(header.data(), std::streamsize(header.size()));
    out.write(reinterpret_cast<const char*>(data->data()), std::streamsize(data->size()));
    out.flush();
    if (!out) throw InputError(fmt::format("{}: write error (disk full?)", file.string()));
  });
}

std::array<double, 2> vlb_norm_range(const VlbHeader& h, NormSource source, VlbWindowUnits units) {
  if (source == NormSource::kWindow) {
    if (units == VlbWindowUnits::kValue) return {h.window_lo, h.window_hi};
    return {h.min + h.window_lo * (h.max - h.min), h.min + h.window_hi * (h.max - h.min)};
  }
  return {h.min, h.max};
}

}  // namespace meltlab::render
