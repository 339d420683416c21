#pragma once
// Volume files: meltlab's own raw samples with a small JSON header, and (render/vdb/openvdb.h)
// OpenVDB's .vdb so a user can bring smoke and cloud volumes from other tools and look at ours
// there.
//
// The header (NAME.json; read through core/config.h: every error is FILE:LINE, unknown keys are
// refused) describes the raw file beside it:
//   {"format": "meltlab-volume", "version": 1,
//    "dims": [nx, ny, nz], "sample_type": "float32" | "uint8" | "uint16",
//    "endianness": "little", "order": "x_fastest",
//    "placement": "cell_centred" | "nodes", "origin": [x, y, z], "spacing": [dx, dy, dz],
//    "value_scale": s,           // value = stored * s
//    "data": "NAME.raw",         // relative to the header's folder
//    "content_hash": "16 hex",   // volume_content_hash of the samples (checked on read)
//    "generator": {...}}         // optional: how the volume was made (kept, not interpreted)
// The raw file holds exactly nx·ny·nz samples, x fastest, little-endian; its size is checked
// against the header (and the sample count against --limits volume_samples) before anything is
// allocated.

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

/// Reads a volume from its JSON header (and the raw file it names) or from a .vdb file (by the
/// extension). Throws InputError naming the file (FILE:LINE for header errors).
Volume read_volume(const std::filesystem::path& file);

}  // namespace meltlab::render
