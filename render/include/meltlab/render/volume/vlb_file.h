#pragma once
// Seed 003's VLB volume file (spec volume-slicing-importance.md §2.1): a text header of seven
// lines, then exactly N_x N_y N_z raw samples, x fastest.
//
//   VLB.1             1  format version (meltlab reads and writes VLB.1)
//   256 256 113       2  dimensions (whole numbers >= 1)
//   int16             3  sample type: int8 | int16 | int32 | uint8 | uint16 | uint32 | float | double
//   little            4  endianness of the samples: little | big
//   1. 1. 2.          5  voxel spacing per axis (finite, > 0)
//   -1117 2248        6  minimum and maximum value (finite, min <= max)
//   0 1               7  recommended window (finite, lo < hi)
//
// Lines end with LF (CR LF is accepted); the samples start right after the seventh line's LF.
// Fields are separated by blanks; anything more or less on a line is refused.
//
// Line 7's units (vsi.data.window_units) are not stated by the source. Its only example, "0 1"
// beside a data range of -1117..2248, reads as fractions of line 6's range (the whole range), so
// that is the default (kFraction: window = min + w (max - min)); kValue takes them as data values.
//
// Reading checks the header (one `FILE:LINE: problem` InputError per refusal: version, a line
// missing or too long, zero/negative/fractional dimensions, an overflowing or over-the-limit
// sample count, an unknown type, a bad endianness, spacing, range or window) and then the file's
// size against the declared sample count before anything is allocated; float samples must be
// finite. Writing is atomic (core/atomic_file.h).

#include <meltlab/render/volume/scalar_volume.h>

#include <bit>
#include <filesystem>
#include <string>

namespace meltlab::render {

/// The header's longest accepted line (bytes, without the LF); the header is read in one piece of
/// at most 7 such lines.
inline constexpr int kVlbMaxLineBytes = 256;

struct VlbHeader {
  std::string version = "VLB.1";
  std::array<int, 3> dims{0, 0, 0};
  ScalarType type = ScalarType::kInt16;
  std::endian endian = std::endian::little;
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();
  double min = 0, max = 0;              ///< line 6
  double window_lo = 0, window_hi = 1;  ///< line 7
  std::int64_t header_bytes = 0;        ///< bytes up to and including the seventh LF (read)

  std::int64_t sample_bytes() const;  ///< N_x N_y N_z × bytes per sample (-1 on overflow)
};

/// vsi.data.window_units.
enum class VlbWindowUnits { kFraction, kValue };

/// Parses a header from the first bytes of a file (`text` may hold the samples after it).
/// Throws InputError "`what`:LINE: problem".
VlbHeader parse_vlb_header(std::string_view text, const std::string& what);
/// The seven lines of a header (numbers printed to round-trip exactly).
std::string format_vlb_header(const VlbHeader& header);

struct VlbFile {
  VlbHeader header;
  ScalarVolume volume;  ///< native byte order, spacing from line 5, origin 0
};

/// Reads and checks a VLB file (see the header comment). Throws InputError naming the file.
VlbFile read_vlb(const std::filesystem::path& file);
/// Reads only the header and checks the file's size against it (no samples are read).
VlbHeader read_vlb_header(const std::filesystem::path& file);

struct VlbWriteOptions {
  std::endian endian = std::endian::little;
  /// Line 6: the scanned range when unset.
  std::optional<std::array<double, 2>> range;
  /// Line 7 (in the reader's default units: fractions of line 6's range).
  std::array<double, 2> window{0.0, 1.0};
};

/// Writes a VLB file atomically (dims, type and spacing from the volume).
void write_vlb(const std::filesystem::path& file, const ScalarVolume& volume, const VlbWriteOptions& options = {});

/// The range a VLB file's header asks for: line 6 (kHeader) or line 7 (kWindow, in `units`).
std::array<double, 2> vlb_norm_range(const VlbHeader& header, NormSource source, VlbWindowUnits units);

}  // namespace meltlab::render
