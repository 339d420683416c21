#pragma once
// The seed-000 test data, generated (spec volume-lighting-raycast.md §3): Perlin's improved noise
// (2002 reference: the 256-entry permutation doubled to 512, fade 6t^5 - 15t^4 + 10t^3, the 12
// cube-edge gradients padded to 16), turbulence with per-octave clipping, and the box and sphere
// turbulence volumes at any resolution (the source's 64^3 and 128^3), plus the figures' fields.
//
// Every generated volume of seed 000 is cell-centred (a box of n^3 cells, as the source's DDS
// textures) with values in [0, 1]; grid position p = ((i + ½)/n, (j + ½)/n, (k + ½)/n) ∈ (0, 1)^3.
// Seed 001's volumes (shapes, skull; volume/shapes.h) are 8-bit node samples with raw values
// 0..255 (value_scale 1), unit spacing from the origin, stored z fastest as the seed's files.

#include <meltlab/render/volume/ct_phantom.h>
#include <meltlab/render/volume/shapes.h>
#include <meltlab/render/volume/volume.h>

#include <cstdint>
#include <string>

namespace meltlab::render {

/// Perlin's improved noise (2002) at a point; nominal range [-1, 1], 0 at integer lattice points.
double improved_noise(double x, double y, double z);

/// vlr.noise.clip_mode: how octaves are clipped to [0, 1] before and after summing.
enum class NoiseClip {
  kPerOctave,  ///< clip each octave to [0, 1], then the sum (the source; the default)
  kSumOnly,    ///< clip only the sum
  kNone,       ///< no clipping (the sum may leave [0, 1])
};

/// vlr.noise.*: T(p) = Σ_{k<octaves} clip(N(base_frequency · lacunarity^k · p + o_k)) / gain^k.
struct TurbulenceOptions {
  int octaves = 4;
  double gain = 2.0;            ///< amplitude divisor per octave (the source's "gain 2")
  double lacunarity = 2.0;      ///< frequency factor per octave
  double base_frequency = 4.0;  ///< noise cells across the unit cube at octave 0
  NoiseClip clip = NoiseClip::kPerOctave;
  std::uint64_t seed = 0;  ///< 0: the reference table as is; else a seeded offset o_k of the domain
};

/// Turbulence at grid position p ∈ [0, 1]^3.
double turbulence(double px, double py, double pz, const TurbulenceOptions& options);

/// The generated volumes.
enum class VolumeKind {
  kTurbulenceBox,     ///< BoxTurb: turbulence filling the box
  kTurbulenceSphere,  ///< SphereTurb: turbulence in the inscribed sphere, fading to its rim
  kFireball,          ///< Fig. 3.4: the sphere's turbulence with density growing with the radius
  kConstant,          ///< every sample = `constant` (closed-form tests, homogeneous slabs)
  kShapes,            ///< seed 001: random cuboids and spheres (ShapesVolume; `shapes` options)
  kSkull,             ///< seed 001: the CT-like head phantom of Table 5.1 (SkullPhantom)
  kCtPhantom,         ///< seed 003: the procedural CT phantom (ct_phantom.h), normalised by its extrema
};

/// vlr.sphere.falloff: φ(ρ) with ρ = r/R, 0 outside the sphere.
enum class SphereFalloff {
  kLinear,  ///< 1 - ρ (the default)
  kNone,    ///< 1 inside the sphere (a hard edge)
};

struct VolumeGenerateOptions {
  VolumeKind kind = VolumeKind::kTurbulenceBox;
  int nx = 64, ny = 64, nz = 64;
  TurbulenceOptions noise;
  SphereFalloff falloff = SphereFalloff::kLinear;
  double constant = 1.0;                      ///< kConstant's value
  SampleType storage = SampleType::kFloat32;  ///< vlr.data.quantization: float32, uint8 or uint16
  ShapesOptions shapes;                       ///< kShapes (its dims are nx, ny, nz); kSkull: its seed
  CtPhantomOptions ct;                        ///< kCtPhantom (its dims are nx, ny, nz)
};

/// Generates the volume (parallel over slices; the result does not depend on the thread count),
/// cell-centred in the unit box [0, 1]^3 (place it with Volume::fit_to_box); kShapes and kSkull:
/// 8-bit node samples z fastest at unit spacing (`storage` ignored); kCtPhantom: float32 node samples
/// at the phantom's spacing, its HU normalised to [0, 1] by the scanned extrema (`storage` ignored). Throws InputError
/// for bad options (dimensions < 1, octaves outside 1..16, frequencies or gain <= 0, shapes that do not fit).
Volume generate_volume(const VolumeGenerateOptions& options);

/// "turbulence_box", "turbulence_sphere", "fireball", "constant", "shapes", "skull", "ct_phantom" (and back; InputError
/// naming `what` for an unknown name).
std::string volume_kind_name(VolumeKind kind);
VolumeKind parse_volume_kind(const std::string& name, const std::string& what);

/// FNV-1a 64 of the volume's dimensions, sample type and stored bytes (x-fastest order), as 16
/// hex digits: names a generated volume and records which one a render read.
std::string volume_content_hash(const Volume& volume);

}  // namespace meltlab::render
