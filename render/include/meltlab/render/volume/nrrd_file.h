#pragma once
// NRRD volumes (teem's "nearly raw raster data", http://teem.sourceforge.net/nrrd/format.html):
// the subset medical users have (3D Slicer, ITK, teem write it), so a CT a user brings can be read
// without conversion.
//
// Why our own reader (issue 17): Debian 12 packages teem (libteem-dev 1.12, 2016 snapshot; small,
// links png/bz2/zlib) and ITK (libinsighttoolkit5-dev, hundreds of MB). Teem's nrrdLoad allocates
// from the header's sizes and reads in one call, with multi-line biff error text and no
// FILE:LINE; meltlab's readers must check the declared sizes against the file and the limits
// before allocating and refuse in one line. The subset below is ~300 lines on zlib (already
// installed with OpenImageIO/OpenVDB; zlib1g-dev in scripts/install-deps), so meltlab reads it
// itself.
//
// Read:
//   NRRD0001 .. NRRD0005 magic; "# comments"; "key:=value" pairs (ignored)
//   type          int8/uint8/int16/uint16/int32/uint32/float/double and their NRRD synonyms
//                 ("short", "unsigned char", "int16_t", ...); 64-bit integers and "block" refused
//   dimension: 3  (anything else refused)
//   sizes         three whole numbers >= 1
//   endian        little | big (required for multi-byte types)
//   encoding      raw | gzip (gz); ascii/text, hex and bzip2 are refused with a clear error
//   spacings      three finite numbers > 0; or
//   space directions  three axis-aligned vectors "(a,0,0) (0,b,0) (0,0,c)": spacing |a|, |b|, |c|
//                 (a negative sign, a mirrored axis, is logged and dropped; oblique or permuted
//                 axes are refused: the Volume is axis-aligned)
//   space origin  "(x,y,z)" (the origin); space / space dimension (recorded, not applied)
//   centers/centerings  cell | node (all three alike; sets the sample placement; default node)
//   data file / datafile  a detached data file (relative to the header's folder); the header is
//                 then NAME.nhdr. "LIST" and formatted file lists are refused.
//   byte skip     >= 0, or -1 (raw only: the data are the file's last bytes); line skip >= 0
//   informative fields (content, kinds, labels, units, space units, measurement frame, min, max,
//                 old min, old max, thicknesses, axis mins/maxs, sample units) are accepted and
//                 ignored; any other field is refused (FILE:LINE).
// The header ends at an empty line (attached data follow) or at the end of a .nhdr file.
// Checks: every refusal is one line naming FILE:LINE (header) or the data file; the raw byte
// count must equal the declared count exactly (after the skips); gzip data must inflate to exactly
// the declared count (inflation stops one byte beyond it: no decompression bombs).
//
// Write: attached (NAME.nrrd) or detached (NAME.nhdr + NAME.raw or NAME.raw.gz), raw or gzip,
// either endianness, with spacings and space origin.

#include <meltlab/render/volume/scalar_volume.h>

#include <bit>
#include <filesystem>
#include <string>

namespace meltlab::render {

enum class NrrdEncoding { kRaw, kGzip };

struct NrrdHeader {
  int version = 4;
  std::array<int, 3> dims{0, 0, 0};
  ScalarType type = ScalarType::kInt16;
  std::endian endian = std::endian::little;
  NrrdEncoding encoding = NrrdEncoding::kRaw;
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  SamplePlacement placement = SamplePlacement::kNodes;
  std::array<bool, 3> mirrored{false, false, false};  ///< negative space directions (dropped)
  std::filesystem::path data_file;                    ///< empty: attached
  std::int64_t byte_skip = 0;                         ///< -1: the data are the file's last bytes
  std::int64_t line_skip = 0;
  std::int64_t header_bytes = 0;  ///< attached: the data start here (after the empty line)

  std::int64_t sample_bytes() const;
};

/// Parses the header at the start of `text` (an attached .nrrd may continue with data). `base_dir`
/// resolves a detached data file. Throws InputError "`what`:LINE: problem".
NrrdHeader parse_nrrd_header(std::string_view text, const std::string& what, const std::filesystem::path& base_dir);

/// Reads a .nrrd or .nhdr file (see the header comment). Throws InputError naming the file.
ScalarVolume read_nrrd(const std::filesystem::path& file, NrrdHeader* header = nullptr);

struct NrrdWriteOptions {
  NrrdEncoding encoding = NrrdEncoding::kRaw;
  std::endian endian = std::endian::little;
};

/// Writes NAME.nrrd (attached) or NAME.nhdr (+ NAME.raw or NAME.raw.gz beside it), atomically.
void write_nrrd(const std::filesystem::path& file, const ScalarVolume& volume, const NrrdWriteOptions& options = {});

}  // namespace meltlab::render
