#pragma once
// Volume files: meltlab's own raw samples with a small JSON header, (render/vdb/openvdb.h)
// OpenVDB's .vdb so a user can bring smoke and cloud volumes from other tools and look at ours
// there, and seed 003's medical formats: VLB (vlb_file.h) and NRRD (nrrd_file.h: .nrrd, .nhdr),
// read as float32 node volumes normalised to [0, 1] (scalar_volume.h, vsi.data.norm_source).
//
// The header (NAME.json; read through core/config.h: every error is FILE:LINE, unknown keys are
// refused) describes the raw file beside it:
//   {"format": "meltlab-volume", "version": 1,
//    "dims": [nx, ny, nz], "sample_type": "float32" | "uint8" | "uint16"
//                                         | "int8" | "int16" | "int32" | "uint32" | "float64",
//    "endianness": "little" | "big", "order": "x_fastest",
//    "placement": "cell_centred" | "nodes", "origin": [x, y, z], "spacing": [dx, dy, dz],
//    "value_scale": s,           // value = stored * s
//    "data": "NAME.raw",         // relative to the header's folder
//    "content_hash": "16 hex",   // volume_content_hash of the samples (checked on read)
//    "generator": {...}}         // optional: how the volume was made (kept, not interpreted)
// The raw file holds exactly nx·ny·nz samples, x fastest, little-endian; its size is checked
// against the header (and the sample count against --limits volume_samples) before anything is
// allocated. float32, uint8 and uint16 little-endian samples are used as stored; the wider types
// (a user's raw CT: int16, big-endian, ...) are converted at load to float32 values = stored ×
// value_scale (default 1), not normalised; their content_hash, if given, is that of the float32
// volume as loaded. meltlab writes only the first three.

#include <meltlab/render/volume/scalar_volume.h>
#include <meltlab/render/volume/vlb_file.h>
#include <meltlab/render/volume/volume.h>

#include <filesystem>
#include <map>
#include <string>

namespace meltlab::render {

/// Writes HEADER (.json) and the raw file named in it (HEADER with .raw), atomically.
/// `generator` (optional) is written as the header's "generator" object: name → value text (numbers
/// and words as they are).
void write_volume(const std::filesystem::path& header, const Volume& volume,
                  const std::map<std::string, std::string>& generator = {});

/// How the medical formats (.vlb, .nrrd, .nhdr) are normalised at load.
struct VolumeReadOptions {
  NormSource norm = NormSource::kScanned;                   ///< vsi.data.norm_source
  VlbWindowUnits window_units = VlbWindowUnits::kFraction;  ///< vsi.data.window_units (VLB line 7)
};

/// What was read (for `volume info` and run records).
struct VolumeReadInfo {
  std::string format;                          ///< "meltlab-volume", "vdb", "vlb", "nrrd"
  std::optional<Normalisation> normalisation;  ///< the medical formats
  std::optional<VlbHeader> vlb;
  std::string stored_type;   ///< the file's sample type (e.g. "int16")
  std::string samples_hash;  ///< the medical formats: scalar_content_hash of the stored samples
};

/// True for the extensions of the medical formats (.vlb, .nrrd, .nhdr).
bool is_medical_volume_file(const std::filesystem::path& file);

/// Reads a volume from its JSON header (and the raw file it names), a .vdb, .vlb, .nrrd or .nhdr
/// file (by the extension). Throws InputError naming the file (FILE:LINE for header errors).
/// `options` apply to the medical formats only (normalise: header and window need a VLB file).
Volume read_volume(const std::filesystem::path& file, const VolumeReadOptions& options = {},
                   VolumeReadInfo* info = nullptr);

/// Writes a volume's stored numbers (uint8, uint16 or float32) as a .vlb, .nrrd or .nhdr file.
void write_medical_volume(const std::filesystem::path& file, const ScalarVolume& volume);

}  // namespace meltlab::render
