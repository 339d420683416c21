#pragma once
// The liquid phase (monograph chapter 7, spec §8.3-8.6): a one-channel float mask on the
// ground plane, spread by the 5×5 filter of Eq. 7.12 and fed each cycle by the object's
// footprint near the ground (the deposit pass, §7.3.2). Liquid is present where
// mask >= p, p a constant or a per-texel threshold texture tp (Eq. 7.7, 7.14).
//
// Grid and frame: the ground is the plane z = const of the mesh's object frame (z up).
// Texel (i, j) — column i along +x, row j along +y — covers
//   [origin.x + i·h, origin.x + (i+1)·h) × [origin.y + j·h, origin.y + (j+1)·h),
// h = texel_size (mesh units); its value is stored at values[j·width + i]. Texture
// coordinates of the monograph: s = (i + ½)/width, t = (j + ½)/height.
//
// Cycle (spec §8.4: 1 spread + 1 deposit per geometry cycle, `liquid_steps_per_cycle`):
//   spread   m'(i,j) = Σ_{di,dj ∈ {-2,-1,1,2}} m(i+di, j+dj) / 16, zero outside (clamp to a
//            black border, `border_mode` = zero). Away from the border it conserves Σ m.
//   deposit  texels whose centre lies under the part of the live mesh with
//            z <= z_min + far_fraction·(z_max - z_min) (the object's current bottom and
//            thickness, re-measured every cycle) receive deposit_value, overwriting
//            (`deposit_blend` overwrite, as a draw into an uncleared render target) or added.
//   An empty mesh deposits nothing: the mask only spreads and fades (assumption 3).
//
// Serial and parallel (TBB, by rows) spreading give bitwise-identical masks: every output
// texel sums its 16 inputs in the same fixed order.

#include <meltlab/sim/mesh.h>

#include <cstdint>
#include <vector>

namespace meltlab::sim {

enum class DepositBlend {
  kOverwrite,  ///< texel = deposit_value (a draw into the uncleared mask; the monograph)
  kAdd,        ///< texel += deposit_value (mass proportional to the footprint's area each cycle)
};

struct LiquidMaskParams {
  int width = 256, height = 256;                     ///< texels (`mask_resolution`)
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< world (x, y) of texel (0, 0)'s lower-left corner
  double texel_size = 1.0;                           ///< h, mesh units per texel (square texels)
  double far_fraction = 0.10;                        ///< `deposit_far_fraction`: slab height / object thickness
  float deposit_value = 1.0f;                        ///< `deposit_value`
  DepositBlend blend = DepositBlend::kOverwrite;     ///< `deposit_blend`
  float threshold = 0.5f;                            ///< p (Eq. 7.7) when no threshold texture is set (`p_threshold`)

  /// Throws InputError naming the field on a bad value.
  void validate() const;
  /// A square grid of `resolution`² texels centred on the mesh's (x, y) bounding box, covering
  /// `extent_factor` times its larger side (room for the puddle to spread).
  static LiquidMaskParams around(const IndexedMesh& mesh, int resolution, double extent_factor = 3.0);
};

/// One spread step (Eq. 7.12, zero border) of a width×height row-major grid: `out` is
/// resized. `parallel` uses TBB over rows; the result is identical either way.
void spread_mask(const std::vector<float>& in, std::vector<float>& out, int width, int height, bool parallel);
/// The monograph's 4-sample form (Eq. 7.13): four bilinear samples at (±1.5, ±1.5) texels
/// with a zero border, averaged. Equal to spread_mask up to float rounding.
void spread_mask_bilinear4(const std::vector<float>& in, std::vector<float>& out, int width, int height);

/// Footprint (0/1 per texel) of the part of the live mesh within the deposit slab.
/// `slab_top_z` is the height below which triangles are drawn (clipped at it).
template <class Real>
std::vector<std::uint8_t> footprint_below(const TriMesh<Real>& mesh, const LiquidMaskParams& params, double slab_top_z);
/// The deposit slab's top: z_min + far_fraction·(z_max - z_min) of the live vertices; NaN if
/// the mesh has no live triangle.
template <class Real>
double deposit_slab_top(const TriMesh<Real>& mesh, double far_fraction);

class LiquidMask {
 public:
  explicit LiquidMask(LiquidMaskParams params);

  /// One liquid cycle: spread, then deposit the footprint of `mesh` (nothing if it is empty).
  void step(const TriMesh<double>& mesh, bool parallel = true);
  void step(const TriMesh<float>& mesh, bool parallel = true);
  /// The two halves of step().
  void spread(bool parallel = true);
  /// Deposits the footprint; returns the number of texels it covered (0 for an empty mesh).
  std::int64_t deposit(const TriMesh<double>& mesh);
  std::int64_t deposit(const TriMesh<float>& mesh);

  /// Per-texel threshold texture tp (Eq. 7.14-7.17), width·height values; empty = constant p.
  void set_threshold_texture(std::vector<float> tp);
  float threshold_at(int i, int j) const {
    return tp_.empty() ? params_.threshold : tp_[static_cast<std::size_t>(j) * params_.width + i];
  }
  /// step(p, mask) at a texel (Eq. 7.7): 1 if liquid is present.
  bool wet(int i, int j) const { return at(i, j) >= threshold_at(i, j); }
  /// Texels with liquid present.
  std::int64_t wet_count() const;
  /// Σ mask (total liquid, texel units).
  double total() const;
  float max_value() const;
  /// True while some texel is at or above its threshold (spreading "ends" when false).
  bool any_wet() const { return wet_count() > 0; }

  float at(int i, int j) const { return values_[static_cast<std::size_t>(j) * params_.width + i]; }
  const std::vector<float>& values() const { return values_; }
  std::vector<float>& values() { return values_; }
  const std::vector<float>& threshold_texture() const { return tp_; }
  const LiquidMaskParams& params() const { return params_; }
  std::int64_t cycles() const { return cycles_; }
  std::int64_t last_footprint_texels() const { return last_footprint_; }

 private:
  LiquidMaskParams params_;
  std::vector<float> values_, scratch_, tp_;
  std::int64_t cycles_ = 0;
  std::int64_t last_footprint_ = 0;
};

}  // namespace meltlab::sim
