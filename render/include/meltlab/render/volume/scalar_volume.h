#pragma once
// The samples of a medical volume file as stored (seed 003, spec volume-slicing-importance.md §2.1):
// signed or unsigned 8-32-bit integers, float or double, x fastest, held in the machine's byte
// order after reading; and their conversion to the renderers' float Volume, normalised to [0, 1]
// (vsi.data.norm_source):
//   f̂ = clamp((f - lo) / (hi - lo), 0, 1)
// with [lo, hi] the scanned extrema (the source's rule: min f̂ = 0 and max f̂ = 1 exactly, since
// (lo - lo)/(hi - lo) = 0 and (hi - lo)/(hi - lo) = 1 in IEEE arithmetic), the file's declared
// range, or its recommended window. A constant volume (lo == hi) normalises to 0 everywhere.
// The VLB reader (vlb_file.h), the NRRD reader (nrrd_file.h), meltlab's raw + JSON header for
// the wider types (volume_io.h) and the CT phantom (ct_phantom.h) share this type.

#include <meltlab/render/volume/volume.h>

#include <Eigen/Core>

#include <array>
#include <bit>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::render {

/// The sample types of medical volume files.
enum class ScalarType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

/// Bytes per sample (1, 2, 4 or 8).
int scalar_bytes(ScalarType type);
/// The VLB names: "int8", "uint8", "int16", "uint16", "int32", "uint32", "float", "double".
std::string scalar_type_name(ScalarType type);
/// The same names back (also "float32", "float64"); nullopt for anything else.
std::optional<ScalarType> parse_scalar_type(const std::string& name);

/// A volume's samples as stored in a file, in native byte order, x fastest.
struct ScalarVolume {
  std::array<int, 3> dims{0, 0, 0};
  ScalarType type = ScalarType::kInt16;
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();  ///< voxel spacing (scene units, e.g. mm)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<std::uint8_t> bytes;  ///< sample_count() * scalar_bytes(type)

  std::int64_t sample_count() const { return std::int64_t(dims[0]) * dims[1] * dims[2]; }
  /// Allocates zeroed samples (dims >= 1; InputError naming `what` beyond volume_samples).
  static ScalarVolume allocate(const std::array<int, 3>& dims, ScalarType type, const std::string& what = "volume");
  /// Sample n (x fastest) as a double (exact for every type).
  double value(std::int64_t n) const;
  double value(int i, int j, int k) const { return value(i + std::int64_t(dims[0]) * (j + std::int64_t(dims[1]) * k)); }
  /// Stores sample n, converted to the type (integers rounded and clamped to the type's range).
  void set_value(std::int64_t n, double v);
  /// The scanned minimum and maximum (NaNs ignored; {0, 0} for an all-NaN volume).
  std::array<double, 2> scanned_range() const;
};

/// Swaps the bytes of every sample (big <-> little endian) in place.
void swap_sample_bytes(std::vector<std::uint8_t>& bytes, ScalarType type);

/// Throws InputError "<what>: sample N is not a finite number" for a float/double volume holding a
/// NaN or an infinity (normalisation and trilinear sampling need finite values); no-op for integers.
void check_finite_samples(const ScalarVolume& volume, const std::string& what);

/// FNV-1a 64 (core/hash.h) of dims, type and the samples as little-endian bytes: names a read or
/// generated file's samples independently of the file format.
std::string scalar_content_hash(const ScalarVolume& volume);

/// vsi.data.norm_source: which range maps to [0, 1].
enum class NormSource {
  kScanned,  ///< the scanned extrema (the source's rule; the default)
  kHeader,   ///< the file's declared minimum and maximum (VLB line 6)
  kWindow,   ///< the file's recommended window (VLB line 7)
  kNone,     ///< no normalisation: the stored values as float (e.g. Hounsfield units)
};
std::string norm_source_name(NormSource s);  ///< "scanned", "header", "window", "none"

/// What a normalisation did (logged and written to run records).
struct Normalisation {
  NormSource source = NormSource::kScanned;
  double lo = 0, hi = 1;  ///< the range mapped to [0, 1] (kNone: unused)
  double scanned_min = 0, scanned_max = 0;
  std::int64_t clipped_low = 0, clipped_high = 0;  ///< samples below lo / above hi (set to 0 / 1)
  bool constant = false;                           ///< lo == hi: every sample normalised to 0
  /// "scanned [-1117, 2248]" etc. (one line, for the log).
  std::string describe() const;
};

/// The float32 node volume of f̂ = clamp((f - lo)/(hi - lo), 0, 1) (lo == hi: 0; kNone: f
/// itself), placed at the volume's origin with its spacing. `lo`/`hi` are used for kHeader and
/// kWindow (the caller resolves them from the file); kScanned scans. Throws InputError (naming
/// `what`) for hi < lo or non-finite bounds.
Volume normalised_volume(const ScalarVolume& volume, NormSource source, double lo, double hi,
                         Normalisation* info = nullptr, const std::string& what = "volume");

/// The stored numbers of a Volume (uint8, uint16 or float32; x fastest) with its spacing and
/// origin, for writing it as a VLB or NRRD file.
ScalarVolume scalar_volume_of(const Volume& volume);

}  // namespace meltlab::render
