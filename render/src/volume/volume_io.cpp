// Volume files: raw samples + JSON header (see volume/volume_io.h); .vdb through render/vdb.

#include <meltlab/render/volume/volume_io.h>

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/config.h>
#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>
#include <meltlab/render/vdb/openvdb.h>
#include <meltlab/render/volume/generate.h>
#include <meltlab/render/volume/nrrd_file.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <bit>
#include <cstring>
#include <fstream>

namespace meltlab::render {

namespace fs = std::filesystem;

static_assert(std::endian::native == std::endian::little, "meltlab's volume files are little-endian");

namespace {

std::string placement_name(SamplePlacement p) { return p == SamplePlacement::kNodes ? "nodes" : "cell_centred"; }

void write_raw(const fs::path& file, const Volume& v) {
  write_atomically(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw InputError(fmt::format("{}: cannot create the file", file.string()));
    const int bytes = sample_bytes(v.type());
    const auto* base = static_cast<const char*>(v.data());
    if (v.x_fastest_packed()) {
      out.write(base, std::streamsize(v.sample_count() * bytes));
    } else {
      const auto st = v.strides();
      for (int k = 0; k < v.nz(); ++k)
        for (int j = 0; j < v.ny(); ++j)
          for (int i = 0; i < v.nx(); ++i) out.write(base + (i * st[0] + j * st[1] + k * st[2]) * bytes, bytes);
    }
    out.flush();
    if (!out) throw InputError(fmt::format("{}: write error (disk full?)", file.string()));
  });
}

Volume read_meltlab_volume(const fs::path& header) {
  const ConfigSection c = load_config(header, "volume header");
  const std::string format = c.require<std::string>("format");
  if (format != "meltlab-volume") c.fail_at("format", fmt::format("not a meltlab volume header (format '{}')", format));
  const int version = c.require<int>("version");
  if (version != 1) c.fail_at("version", fmt::format("unsupported version {} (this meltlab reads 1)", version));
  const auto dims = c.require_numbers("dims", 3, 3);
  for (double d : dims)
    if (!(d >= 1 && d <= 2147483647.0 && d == std::floor(d)))
      c.fail_at("dims", "'dims' must be three whole numbers >= 1");
  const std::string type = c.get_choice("sample_type", "float32",
                                        {"float32", "uint8", "uint16", "int8", "int16", "int32", "uint32", "float64"});
  const bool big = c.get_choice("endianness", "little", {"little", "big"}) == "big";
  c.get_choice("order", "x_fastest", {"x_fastest"});
  const std::string placement = c.get_choice("placement", "cell_centred", {"cell_centred", "nodes"});
  const Eigen::Vector3d origin = c.get_vec3("origin", Eigen::Vector3d::Zero());
  const Eigen::Vector3d spacing = c.get_vec3("spacing", Eigen::Vector3d::Ones());
  if (!(spacing.minCoeff() > 0)) c.fail_at("spacing", "'spacing' must be three numbers > 0");
  // float32, uint8 and uint16 little-endian: used as stored; anything else converted to float32.
  const bool as_stored = !big && (type == "float32" || type == "uint8" || type == "uint16");
  const SampleType st = !as_stored         ? SampleType::kFloat32
                        : type == "uint8"  ? SampleType::kUint8
                        : type == "uint16" ? SampleType::kUint16
                                           : SampleType::kFloat32;
  const double scale = c.get<double>("value_scale", !as_stored                  ? 1.0
                                                    : st == SampleType::kUint8  ? 1.0 / 255
                                                    : st == SampleType::kUint16 ? 1.0 / 65535
                                                                                : 1.0);
  if (!(scale > 0)) c.fail_at("value_scale", "'value_scale' must be > 0");
  const std::string data = c.require<std::string>("data");
  const auto hash = c.optional<std::string>("content_hash");
  c.ignore("generator");
  c.finish();

  const int nx = int(dims[0]), ny = int(dims[1]), nz = int(dims[2]);
  const std::int64_t count = checked_mul(checked_mul(nx, ny), nz);
  if (count < 0) c.fail_at("dims", "'dims' overflow: the sample count is too large");
  check_count(header.string(), "volume samples", count, input_limits().volume_samples, "volume_samples");
  const fs::path raw = fs::path(data).is_absolute() ? fs::path(data) : header.parent_path() / data;
  const std::int64_t size = check_input_file(raw, "raw volume");
  const ScalarType stored = *parse_scalar_type(type);
  const std::int64_t expected = checked_mul(count, scalar_bytes(stored));
  if (size != expected)
    throw InputError(fmt::format("{}: holds {} bytes, but its header {} declares {} x {} x {} {} samples = {} bytes",
                                 raw.string(), size, header.string(), nx, ny, nz, type, expected));
  Volume v;
  std::ifstream in(raw, std::ios::binary);
  if (as_stored) {
    v = Volume::allocate(nx, ny, nz, st, header.string());
    in.read(static_cast<char*>(v.mutable_data()), std::streamsize(expected));
    if (in.gcount() != std::streamsize(expected)) throw InputError(fmt::format("{}: read error", raw.string()));
  } else {
    ScalarVolume s = ScalarVolume::allocate({nx, ny, nz}, stored, header.string());
    in.read(reinterpret_cast<char*>(s.bytes.data()), std::streamsize(expected));
    if (in.gcount() != std::streamsize(expected)) throw InputError(fmt::format("{}: read error", raw.string()));
    if (big) swap_sample_bytes(s.bytes, stored);
    check_finite_samples(s, raw.string());
    v = normalised_volume(s, NormSource::kNone, 0, 0, nullptr, header.string());
  }
  v.set_placement(placement == "nodes" ? SamplePlacement::kNodes : SamplePlacement::kCellCentred);
  v.set_origin(origin);
  v.set_spacing(spacing);
  v.set_value_scale(scale);
  if (st == SampleType::kFloat32) {
    const auto* f = static_cast<const float*>(v.data());
    for (std::int64_t i = 0; i < count; ++i)
      if (!std::isfinite(f[i])) throw InputError(fmt::format("{}: sample {} is not a finite number", raw.string(), i));
  }
  if (hash && *hash != volume_content_hash(v))
    throw InputError(fmt::format("{}: the samples do not match the header's content_hash {} (the raw file changed?)",
                                 raw.string(), *hash));
  return v;
}

}  // namespace

void write_volume(const fs::path& header, const Volume& v, const std::map<std::string, std::string>& generator) {
  if (header.extension() == ".vdb") {
    write_vdb(header, v);
    return;
  }
  fs::path raw = header;
  raw.replace_extension(".raw");
  nlohmann::ordered_json j;
  j["format"] = "meltlab-volume";
  j["version"] = 1;
  j["dims"] = {v.nx(), v.ny(), v.nz()};
  j["sample_type"] = sample_type_name(v.type());
  j["endianness"] = "little";
  j["order"] = "x_fastest";
  j["placement"] = placement_name(v.placement());
  j["origin"] = {v.origin().x(), v.origin().y(), v.origin().z()};
  j["spacing"] = {v.spacing().x(), v.spacing().y(), v.spacing().z()};
  j["value_scale"] = v.value_scale();
  j["data"] = raw.filename().string();
  j["content_hash"] = volume_content_hash(v);
  if (!generator.empty()) {
    nlohmann::ordered_json g = nlohmann::ordered_json::object();
    for (const auto& [k, val] : generator) {
      // Numbers stay numbers, everything else is a string.
      char* end = nullptr;
      const double d = std::strtod(val.c_str(), &end);
      if (!val.empty() && end && *end == '\0' && std::isfinite(d))
        g[k] = d;
      else
        g[k] = val;
    }
    j["generator"] = g;
  }
  write_raw(raw, v);
  write_text_atomically(header, j.dump(2) + "\n");
}

bool is_medical_volume_file(const fs::path& file) {
  const std::string ext = file.extension().string();
  return ext == ".vlb" || ext == ".nrrd" || ext == ".nhdr";
}

Volume read_volume(const fs::path& file, const VolumeReadOptions& options, VolumeReadInfo* info) {
  VolumeReadInfo local;
  VolumeReadInfo& r = info ? *info : local;
  const std::string ext = file.extension().string();
  if (ext == ".vdb") {
    r.format = "vdb";
    Volume v = read_vdb(file);
    r.stored_type = sample_type_name(v.type());
    return v;
  }
  if (ext == ".vlb") {
    const VlbFile f = read_vlb(file);
    r.format = "vlb";
    r.vlb = f.header;
    r.stored_type = scalar_type_name(f.header.type);
    r.samples_hash = scalar_content_hash(f.volume);
    const auto range = vlb_norm_range(f.header, options.norm, options.window_units);
    Normalisation n;
    Volume v = normalised_volume(f.volume, options.norm, range[0], range[1], &n, file.string());
    r.normalisation = n;
    return v;
  }
  if (ext == ".nrrd" || ext == ".nhdr") {
    if (options.norm == NormSource::kHeader || options.norm == NormSource::kWindow)
      throw InputError(
          fmt::format("{}: normalise: {} needs a VLB file (a NRRD file declares no range or window; "
                      "use scanned or none)",
                      file.string(), norm_source_name(options.norm)));
    NrrdHeader h;
    const ScalarVolume s = read_nrrd(file, &h);
    r.format = "nrrd";
    r.stored_type = scalar_type_name(s.type);
    r.samples_hash = scalar_content_hash(s);
    Normalisation n;
    Volume v = normalised_volume(s, options.norm, 0, 0, &n, file.string());
    v.set_placement(h.placement);
    r.normalisation = n;
    return v;
  }
  r.format = "meltlab-volume";
  Volume v = read_meltlab_volume(file);
  r.stored_type = sample_type_name(v.type());
  return v;
}

void write_medical_volume(const fs::path& file, const ScalarVolume& volume) {
  const std::string ext = file.extension().string();
  if (ext == ".vlb")
    write_vlb(file, volume);
  else if (ext == ".nrrd" || ext == ".nhdr")
    write_nrrd(file, volume);
  else
    throw InputError(fmt::format("{}: not a medical volume file name (.vlb, .nrrd or .nhdr)", file.string()));
}

}  // namespace meltlab::render
