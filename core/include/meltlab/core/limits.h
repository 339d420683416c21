#pragma once
// Resource limits on inputs. A reader checks a file's declared counts against the file's size
// and against these caps BEFORE it allocates, so a 20-byte file that claims two billion
// vertices, or a PNG header that claims 30000 x 30000 pixels, is refused with a one-line error
// instead of taking the machine down.
//
// The limits are process-wide (they describe the machine and the user's intent, not one call):
// defaults below; the environment variable MELTLAB_LIMITS and the command-line option
// `meltlab --limits` override them, e.g.
//   MELTLAB_LIMITS="mesh_elements=1e8,image_pixels=5e8"
// and child processes started by meltlab inherit them through the environment.

#include <cstdint>
#include <string>
#include <string_view>

namespace meltlab {

struct InputLimits {
  /// Vertices, and faces, of one mesh file: 20 M each (a 20 M-triangle mesh needs ~2 GB in the
  /// melt cycle; the largest meshes of the harness have 7.8 M).
  std::int64_t mesh_elements = 20'000'000;
  /// Pixels (width x height) of one image: 2^27 = 134 M (e.g. 16384 x 8192; 2 GB as RGBA float).
  std::int64_t image_pixels = std::int64_t{1} << 27;
  /// Samples of one volume (nx * ny * nz): 2^33 = 8.6 G (a 2000^3 8-bit volume, memory-mapped).
  std::int64_t volume_samples = std::int64_t{1} << 33;
  /// Bytes of one text input (YAML/JSON configs and manifests, CSV series, text grids): 256 MiB.
  std::int64_t text_bytes = std::int64_t{1} << 28;
};

/// The limits in force (defaults, then MELTLAB_LIMITS, then set_input_limits).
const InputLimits& input_limits();
/// Replaces the limits for this process and exports them in MELTLAB_LIMITS so child processes
/// apply the same ones.
void set_input_limits(const InputLimits& limits);
/// Parses "name=value,name=value" (names: mesh_elements, image_pixels, volume_samples,
/// text_bytes; values are positive integers or numbers like 1e8) on top of `base`. Throws
/// InputError naming `what` (the option or variable) on a bad list.
InputLimits parse_input_limits(std::string_view text, const InputLimits& base, const std::string& what);
/// The limits as "name=value,..." (the form parse_input_limits reads).
std::string describe_input_limits(const InputLimits& limits);

/// Throws InputError "<file>: <what> <count> exceeds the limit of <limit> (raise it with
/// --limits <name>=N)" if count > limit, and "<file>: <what> <count> is negative" if count < 0.
void check_count(const std::string& file, std::string_view what, std::int64_t count, std::int64_t limit,
                 std::string_view limit_name);

/// a * b for non-negative a and b, or -1 if either is negative or the product overflows int64.
std::int64_t checked_mul(std::int64_t a, std::int64_t b);

}  // namespace meltlab
