#include <meltlab/core/run_folder.h>
#include <meltlab/core/config.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/hash.h>
#include <meltlab/experiments/compare_run.h>
#include <meltlab/experiments/fit_run.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/kl_field.h>
#include <meltlab/sim/mesh_sequence.h>
#include <meltlab/sim/quality.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/experiments/series_output.h>
#include <meltlab/verify/fit_parameters.h>
#include <meltlab/verify/mass_series.h>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, sep)) out.push_back(item);
  return out;
}

/// The YAML node at a dotted path below the document ("kl.of.0.strength"); sequences are
/// indexed by number. Throws InputError "FILE:LINE: PATH: ..." at the last node reached.
YAML::Node node_at(const YAML::Node& doc, const std::string& path, const std::string& source) {
  YAML::Node n = doc;
  std::string reached;  // the part of `path` walked so far
  for (const std::string& key : split(path, '.')) {
    const ConfigValue here(n, source, reached);
    if (n.IsMap()) {
      if (!n[key]) here.fail(fmt::format("{}: no key '{}'", path, key));
      n.reset(n[key]);
    } else if (n.IsSequence()) {
      std::size_t i = 0;
      try {
        i = std::stoul(key);
      } catch (const std::exception&) {
        here.fail(fmt::format("{}: '{}' is not an index of a list", path, key));
      }
      if (i >= n.size()) here.fail(fmt::format("{}: index {} beyond the list's {} items", path, i, n.size()));
      n.reset(n[i]);
    } else {
      here.fail(fmt::format("{}: '{}' is below a plain value", path, key));
    }
    reached += (reached.empty() ? "" : ".") + key;
  }
  return n;
}

double number_at(const YAML::Node& doc, const std::string& path, const std::string& source) {
  const ConfigValue v(node_at(doc, path, source), source, path);
  if (!v.is_scalar()) v.fail("not a number (only numbers can be fitted)");
  return v.as<double>();
}

class EmpiricalModel final : public verify::FitModel {
 public:
  EmpiricalModel(std::shared_ptr<const PreparedSimulation> p, YAML::Node kl_doc)
      : p_(std::move(p)), kl_doc_(std::move(kl_doc)) {}

  std::unique_ptr<sim::MeshSequence> start(const std::map<std::string, double>& values) override {
    sim::MeltParams params = p_->params;
    sim::KlFieldPtr kl = p_->kl;
    bool kl_changed = false;
    YAML::Node doc = kl_doc_ ? YAML::Clone(kl_doc_) : YAML::Node();
    for (const auto& [name, v] : values) {
      if (name == "kg") {
        params.kg = v;
      } else if (name == "kn") {  // in the --kn units: relative to L0 unless --units absolute
        params.kN = v * p_->coefficient_unit();
      } else if (verify::fit_parameter_role(name) == verify::FitParameterRole::kKlField) {
        YAML::Node leaf = node_at(doc, name, p_->opt.kl_file.string());
        leaf = v;
        kl_changed = true;
      }
    }
    params.validate();
    if (kl_changed) {
      sim::KlContext ctx;
      const auto q = sim::mesh_quality(sim::TriMesh<double>::from_indexed(p_->mesh));
      ctx.bbox_min = q.bbox_min;
      ctx.bbox_max = q.bbox_max;
      ctx.base_dir = p_->opt.kl_file.parent_path();
      kl = sim::parse_kl_field(doc["kl"], p_->opt.kl_file.string(), ctx);
    }
    return std::make_unique<sim::MeltReplay>(p_->mesh, params, kl, p_->opt.double_precision);
  }

 private:
  std::shared_ptr<const PreparedSimulation> p_;
  YAML::Node kl_doc_;
};

}  // namespace

std::vector<verify::FitParameter> fit_parameters(const FitRunOptions& o, double kg_initial,
                                                 const std::map<std::string, double>& kl_values, bool series_only) {
  verify::FitParameterContext context;
  context.kg_initial = kg_initial;
  context.kE = o.simulation.kE;
  context.kn_initial = o.simulation.kN.value_or(o.simulation.kE / 100.0);
  context.cycles_per_photo = o.cycles_per_photo;
  context.series_only = series_only;
  context.seconds_per_cycle = o.seconds_per_cycle.value_or(1.0);
  // By name: the order of the fit's parameter vector.
  std::map<std::string, verify::FitParameterSpec> known;
  for (verify::FitParameterSpec& spec : verify::fit_parameter_table(context)) known[spec.name] = std::move(spec);
  for (const auto& [name, v] : kl_values) known[name] = verify::kl_fit_parameter(name, v);
  // A photo parameter named for a mass series: say why it is unknown there.
  auto check_known = [&](const std::string& option, const std::string& name) {
    if (known.count(name) > 0) return;
    const bool photo_only =
        name == verify::kRegistrationGroup || name == "cycles_per_photo" || name.rfind("reg.", 0) == 0;
    if (series_only && photo_only)
      throw InputError(fmt::format("{}: {} needs photos; the observations are a mass series alone (parameters: {})",
                                   option, name, verify::fit_parameter_names(true)));
    throw InputError(
        fmt::format("{}: unknown parameter '{}' ({})", option, name, verify::fit_parameter_names(series_only)));
  };

  std::set<std::string> free;
  std::vector<std::string> fit_names = o.fit;
  if (fit_names.empty())
    fit_names = series_only ? std::vector<std::string>{"kg"}
                            : std::vector<std::string>{"kg", std::string(verify::kRegistrationGroup)};
  for (const std::string& f : fit_names) {
    if (f == verify::kRegistrationGroup && !series_only) {
      for (const std::string& r : verify::registration_parameter_names()) free.insert(r);
    } else {
      check_known("--fit", f);
      free.insert(f);
    }
  }
  for (const auto& [name, v] : o.fix) {
    if (series_only)
      check_known("--fix", name);
    else
      require(known.count(name) > 0, fmt::format("--fix: unknown parameter '{}'", name));
    free.erase(name);
  }
  std::vector<verify::FitParameter> out;
  for (const auto& [name, spec] : known) {
    verify::FitParameter p;
    p.name = name;
    p.initial = spec.initial;
    p.lower = spec.lower;
    p.upper = spec.upper;
    p.scale = spec.scale;
    if (auto it = o.initial.find(name); it != o.initial.end()) p.initial = it->second;
    if (auto it = o.fix.find(name); it != o.fix.end()) p.initial = it->second;
    if (auto it = o.bounds.find(name); it != o.bounds.end()) {
      p.lower = it->second.first;
      p.upper = it->second.second;
      require(p.lower < p.upper, fmt::format("--bound {}: lower {} must be below upper {}", name, p.lower, p.upper));
    }
    p.fixed = free.count(name) == 0;
    require(std::isfinite(p.initial) && p.lower <= p.initial && p.initial <= p.upper,
            fmt::format("{} = {} lies outside its bounds [{}, {}]", name, p.initial, p.lower, p.upper));
    if (name == "seconds_per_cycle") p.scale = 0.05 * p.initial;  // the table's 5 %, of the start given
    out.push_back(p);
  }
  for (const auto& [name, v] : o.initial) {
    if (series_only) check_known("--initial", name);
    require(known.count(name) > 0, fmt::format("--initial: unknown parameter '{}'", name));
  }
  for (const auto& [name, v] : o.bounds) {
    if (series_only) check_known("--bound", name);
    require(known.count(name) > 0, fmt::format("--bound: unknown parameter '{}'", name));
  }
  return out;
}

namespace {

/// The kl field numbers named by --fit, --fix, --initial or --bound, read from the --kl file
/// (loaded into `kl_doc` when one is named).
std::map<std::string, double> kl_parameter_values(const FitRunOptions& o, const PreparedSimulation& prepared,
                                                  YAML::Node& kl_doc) {
  std::map<std::string, double> kl_values;
  std::vector<std::string> names = o.fit;
  for (const auto& m : {o.fix, o.initial})
    for (const auto& [k, v] : m) names.push_back(k);
  for (const auto& [k, v] : o.bounds) names.push_back(k);
  for (const std::string& name : names) {
    if (verify::fit_parameter_role(name) != verify::FitParameterRole::kKlField) continue;
    require(!o.simulation.kl_file.empty(), fmt::format("{}: fitting a kl parameter needs --kl FILE", name));
    // (A default YAML::Node is a defined null node, so `!kl_doc` would never be true.)
    if (kl_doc.IsNull()) kl_doc = load_yaml_file(prepared.opt.kl_file, "kl field");
    kl_values[name] = number_at(kl_doc, name, o.simulation.kl_file.string());
  }
  return kl_values;
}

/// The manifest's mass/volume series in m³ over the fitted photos (before the held-out ones).
verify::VolumeSeries volume_series(const verify::ObservationSequence& obs, int n_fit) {
  require(obs.mass_series.has_value(),
          fmt::format("{}: --volume-weight needs a mass_series in the manifest", obs.manifest.string()));
  const verify::TimeSeries ts = verify::read_time_series(*obs.mass_series);
  verify::VolumeSeries vs;
  const double held_out_time = obs.interval_s ? *obs.interval_s * n_fit : kInf;
  for (std::size_t i = 0; i < ts.time_s.size(); ++i) {
    if (ts.time_s[i] >= held_out_time) break;
    double v = ts.value[i];
    if (ts.quantity == "mass_g")
      v = v / 1000.0 / verify::kIceDensity;
    else if (ts.quantity == "mass_kg")
      v = v / verify::kIceDensity;
    else if (ts.quantity == "volume_cm3")
      v = v * 1e-6;
    vs.time_s.push_back(ts.time_s[i]);
    vs.volume_m3.push_back(v);
  }
  require(!vs.time_s.empty() && vs.volume_m3.front() > 0,
          fmt::format("{}: no usable volume sample in the fitted time range", obs.mass_series->string()));
  return vs;
}

/// The fitted run (model at the estimates, the fitted time scale and registration) against
/// every photo, held-out ones included; writes DIR/comparison.
verify::CompareResult compare_fitted_run(const verify::ObservationSequence& obs, verify::FitModel& model,
                                         const verify::FitResult& fit, const FitRunOptions& o, const fs::path& dir,
                                         const std::function<void(const std::string&)>& log) {
  std::map<std::string, double> model_values;
  for (const auto& e : fit.estimates)
    if (verify::is_model_parameter(e.name)) model_values[e.name] = e.value;
  auto meshes = model.start(model_values);
  verify::CompareOptions copt;
  copt.mapping.cycles_per_photo = fit.cycles_per_photo();
  copt.mapping.first_cycle = o.first_cycle;
  copt.registration = verify::RegistrationMode::kGiven;
  copt.given_registration = fit.registration();
  if (log) log("comparing the fitted run with every photo");
  return compare_and_write(obs, *meshes, copt, dir, o.overlay_every, {});
}

json optional_json(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }

/// Every parameter: value, start, fixed, at a bound, and its errors (fit.json "estimates").
json estimates_json(const verify::FitResult& fit, bool photos) {
  json est = json::object();
  for (const auto& e : fit.estimates) {
    est[e.name] = {{"value", e.value},
                   {"initial", e.initial},
                   {"fixed", e.fixed},
                   {"at_bound", e.at_bound},
                   {"standard_error", optional_json(e.standard_error)},
                   {"standard_error_clustered", optional_json(e.standard_error_clustered)}};
    if (photos) est[e.name]["segmentation_bias"] = optional_json(e.segmentation_bias);
    est[e.name]["standard_error_total"] = optional_json(e.standard_error_total);
  }
  return est;
}

/// What the errors of "estimates" mean (fit.json "uncertainty"; verify/fit.h).
/// What the solver did (fit.json and the mass fit's JSON): iterations, simulations, time,
/// convergence, and the kg scan of the start.
void add_solver_json(json& j, const verify::FitResult& fit) {
  j["iterations"] = fit.iterations;
  j["simulations"] = fit.simulations;
  j["uncertainty_simulations"] = fit.uncertainty_evaluations;
  j["time_s"] = fit.time_s;
  j["converged"] = fit.converged;
  j["message"] = fit.message;
  json scan = json::array();
  for (const auto& [kg, cost] : fit.kg_scan) scan.push_back({{"kg", kg}, {"cost", cost}});
  j["kg_scan"] = scan;
}

json uncertainty_json(const verify::FitResult& fit, bool photos) {
  json u;
  u["standard_error"] =
      "Ceres' covariance scaled by the residual variance: every residual counted as independent. Not to be trusted "
      "for photos: the ~50 contour residuals of one photo are not independent (too small or too large).";
  u["standard_error_clustered"] = fmt::format(
      "cluster-robust (sandwich) covariance, one cluster per {}, times G/(G-1): the statistical error, "
      "estimate ± 1.96 of it covers the truth about 95 % of the time when nothing else is wrong",
      photos ? "photo" : fmt::format("run of {} consecutive readings", fit.readings_per_cluster));
  u["clusters"] = fit.clusters;
  u["correlation_clustered"] = fit.correlation_clustered;
  if (photos) {
    u["segmentation_bias"] =
        "a systematic error, in neither standard error above: the estimate minus the estimate from contours at the "
        "level half-way between ice and ground next to each contour (one Gauss-Newton step from the optimum). Its "
        "size is that of the error the segmentation's level makes; its sign is no reliable correction.";
    u["standard_error_total"] =
        "sqrt(standard_error_clustered² + segmentation_bias²): the error bar to quote (statistical and segmentation "
        "errors together; the fit_coverage experiment measures how often ±1.96 of it holds the truth)";
    json off = nullptr;
    if (!fit.segmentation_offset_px.empty()) {
      double sum = 0, lo = fit.segmentation_offset_px.front(), hi = lo;
      for (double v : fit.segmentation_offset_px) sum += v, lo = std::min(lo, v), hi = std::max(hi, v);
      off = {{"mean", sum / static_cast<double>(fit.segmentation_offset_px.size())}, {"min", lo}, {"max", hi}};
    }
    u["segmentation_offset_px"] = off;
  } else {
    u["standard_error_total"] = "the clustered error (a series has no segmentation)";
  }
  return u;
}

/// fit.json without its provenance: the library's FitResult and CompareResult, written here
/// at the edge.
json fit_json(const verify::ObservationSequence& obs, const FitRunOptions& o, const verify::FitResult& fit,
              const verify::CompareResult& cmp, int n_fit) {
  json j;
  const int n_frames = static_cast<int>(obs.frames.size());
  j["observations"] = {{"manifest", fs::absolute(obs.manifest).string()},
                       {"manifest_hash", file_hash(obs.manifest)},
                       {"frames", n_frames},
                       {"object", obs.object}};
  j["simulation"] = options_to_json(o.simulation);
  const json est = estimates_json(fit, true);
  j["estimates"] = est;
  j["free"] = fit.free_names;
  j["correlation"] = fit.correlation;
  j["cost"] = {{"initial", fit.initial_cost}, {"final", fit.final_cost}, {"residual_sigma_px", fit.residual_sigma_px}};
  j["uncertainty"] = uncertainty_json(fit, true);
  j["warnings"] = fit.warnings;
  add_solver_json(j, fit);
  j["frames_used"] = fit.frames_used.size();
  j["frames_refused"] = fit.frames_refused;
  j["frame_rms_px"] = fit.frame_rms_px;
  j["registration"] = {{"pivot_px", {fit.pivot_px.x(), fit.pivot_px.y()}},
                       {"scale", fit.registration().scale},
                       {"angle_deg", fit.registration().angle_rad * 180.0 / 3.14159265358979323846},
                       {"tx_px", fit.registration().translation.x()},
                       {"ty_px", fit.registration().translation.y()}};
  // P on the fitted and the held-out frames.
  auto p_stats = [&](int from, int to) {
    double sum = 0, mx = 0;
    int n = 0;
    for (const auto& f : cmp.frames) {
      if (f.status != "ok" || f.frame < from || f.frame >= to) continue;
      sum += f.pixels.P;
      mx = std::max(mx, f.pixels.P);
      ++n;
    }
    return json{{"frames", n}, {"P_mean", n ? json(sum / n) : json(nullptr)}, {"P_max", n ? json(mx) : json(nullptr)}};
  };
  j["P_fitted_frames"] = p_stats(0, n_fit);
  j["P_held_out_frames"] = p_stats(n_fit, n_frames);
  j["holdout"] = o.holdout;
  j["comparison"] = summarize_frames(cmp.frames);
  // The truth, when the sequence was made by synth-sequence (inverse-crime data).
  if (obs.ground_truth) {
    try {
      const json truth = json::parse(read_text_file(*obs.ground_truth, "ground truth"));
      json t;
      if (truth.contains("simulation") && truth["simulation"].contains("kg")) t["kg"] = truth["simulation"]["kg"];
      if (truth.contains("cycles_per_photo")) t["cycles_per_photo"] = truth["cycles_per_photo"];
      if (truth.contains("misalignment")) t["misalignment"] = truth["misalignment"];
      if (t.contains("kg") && est.contains("kg"))
        t["kg_relative_error"] = (est["kg"]["value"].get<double>() - t["kg"].get<double>()) / t["kg"].get<double>();
      j["truth"] = t;
    } catch (const std::exception& e) {
      j["truth"] = {{"error", e.what()}};
    }
  }
  return j;
}

/// The fitted model's mass curve: one point per cycle from t = 0 (cycle first_cycle) until it
/// has fallen below 1 % of the initial mass after `t_end`, or at 3 t_end (or max_cycles).
verify::MassCurve fitted_mass_curve(verify::FitModel& model, const verify::FitResult& fit, double mass0_g,
                                    double first_cycle, double t_end, std::int64_t max_cycles) {
  std::map<std::string, double> values;
  for (const auto& e : fit.estimates)
    if (verify::is_model_parameter(e.name)) values[e.name] = e.value;
  const double S = fit.value("seconds_per_cycle");
  auto seq = model.start(values);
  auto volume_at = [&](std::int64_t c) {
    const sim::TriMesh<double>& m = seq->mesh_at(c);
    return m.live_triangle_count() > 0 ? sim::mesh_volume(m) : 0.0;
  };
  const double v0 = volume_at(0);
  const auto c0 = static_cast<std::int64_t>(std::floor(first_cycle));
  verify::MassCurve curve;
  double previous = v0;
  if (c0 > 0) previous = volume_at(c0);
  const double w = first_cycle - static_cast<double>(c0);
  for (std::int64_t c = c0 + 1; c <= max_cycles; ++c) {
    const double v = volume_at(c);
    if (curve.time_s.empty()) {  // t = 0: between cycles c0 and c0 + 1
      curve.time_s.push_back(0.0);
      curve.mass_g.push_back(mass0_g * ((1.0 - w) * previous + w * v) / v0);
    }
    curve.time_s.push_back((static_cast<double>(c) - first_cycle) * S);
    curve.mass_g.push_back(mass0_g * v / v0);
    if (curve.time_s.back() > t_end && (curve.mass_g.back() < 0.01 * mass0_g || curve.time_s.back() > 3 * t_end)) break;
    previous = v;
  }
  return curve;
}

/// `meltlab fit` on a mass series alone (fit_run.h).
json run_series_fit(const FitRunOptions& o, const verify::ObservationSequence& obs,
                    const std::shared_ptr<const PreparedSimulation>& prepared, const YAML::Node& kl_doc,
                    const std::map<std::string, double>& kl_values, const fs::path& dir,
                    const std::function<void(const std::string&)>& log) {
  const std::string manifest = obs.manifest.string();
  require(o.holdout == 0, "--holdout: photos are held out; a mass series is fitted whole");
  require(!o.cycles_per_photo_given,
          fmt::format("--cycles-per-photo: {} has no photos; the time scale of a mass series is --seconds-per-cycle",
                      manifest));
  if (o.seconds_per_cycle)
    require(std::isfinite(*o.seconds_per_cycle) && *o.seconds_per_cycle > 0,
            fmt::format("--seconds-per-cycle: must be a number > 0 (got {})", *o.seconds_per_cycle));
  require(std::isfinite(o.density_kg_m3) && o.density_kg_m3 > 0, "--density: must be a number > 0");
  const std::vector<verify::FitParameter> params = fit_parameters(o, o.simulation.kg, kl_values, true);
  const auto S = std::find_if(params.begin(), params.end(),
                              [](const verify::FitParameter& p) { return p.name == "seconds_per_cycle"; });
  require(S != params.end() && (!S->fixed || o.seconds_per_cycle || o.fix.count("seconds_per_cycle")),
          fmt::format("{}: a mass series needs the time scale: give --seconds-per-cycle S to fit kg, or fit the time "
                      "scale (--fit seconds_per_cycle, kg fixed by --kg)",
                      manifest));
  const verify::MeltSeries series = load_melt_series(obs, o.density_kg_m3);
  std::string mass_from;
  const double m0 = initial_mass_g(series, o.mass_g, mass_from);
  for (const std::string& s : series.left_out) log("left out " + s);

  // The readings as volumes; the one the mesh is scaled to is not a residual.
  const std::size_t first = o.mass_g ? 0 : 1;
  const double g_per_m3 = o.density_kg_m3 * 1000.0;
  verify::VolumeSeries vs;
  for (std::size_t i = first; i < series.time_s.size(); ++i) {
    vs.time_s.push_back(series.time_s[i]);
    vs.volume_m3.push_back(series.mass_g[i] / g_per_m3);
  }
  vs.initial_volume_m3 = m0 / g_per_m3;
  verify::FitOptions fo = o.fit_options;
  fo.first_cycle = o.first_cycle;
  fo.frames.clear();
  fo.volume_weight = 1.0;
  fo.log = log;
  fo.start_time_scale = !S->fixed && !o.seconds_per_cycle && !o.initial.count("seconds_per_cycle");

  EmpiricalModel model(prepared, kl_doc);
  const verify::FitResult fit = verify::fit_sequence(obs, model, params, fo, vs);
  const verify::MassCurve curve = fitted_mass_curve(model, fit, m0, o.first_cycle, series.time_s.back(), fo.max_cycles);
  require(curve.time_s.back() >= series.time_s.back(),
          fmt::format("fit: the fitted model does not reach the last reading within {} cycles", fo.max_cycles));
  const verify::SeriesComparison cmp = verify::compare_series(verify::mass_curve(series), curve, m0, 0.02, first);
  write_mass_curve_csv(dir / "mass_curve.csv", series, curve, "fitted");
  verify::write_image(
      dir / "mass_curve.png",
      verify::mass_curve_image(
          verify::mass_curve(series),
          {{fmt::format("empirical model, kg {:.4g}, {:.4g} s/cycle", fit.value("kg"), fit.value("seconds_per_cycle")),
            curve}},
          fmt::format("{}: mass of the ice", obs.object.empty() ? "series" : obs.object), 0.02 * m0,
          series.left_out_readings));

  json j;
  j["observations"] = {{"manifest", fs::absolute(obs.manifest).string()},
                       {"manifest_hash", file_hash(obs.manifest)},
                       {"frames", 0},
                       {"object", obs.object},
                       {"series", series_json(series)}};
  j["initial_mass_g"] = {{"value", m0}, {"from", mass_from}, {"density_kg_m3", o.density_kg_m3}};
  j["simulation"] = options_to_json(o.simulation);
  j["estimates"] = estimates_json(fit, false);
  j["free"] = fit.free_names;
  j["correlation"] = fit.correlation;
  // Residuals are relative masses (model - reading) / initial mass.
  j["cost"] = {{"initial", fit.initial_cost},
               {"final", fit.final_cost},
               {"residual_sigma_relative", fit.residual_sigma_px},
               {"residual_sigma_g", fit.residual_sigma_px * m0}};
  j["uncertainty"] = uncertainty_json(fit, false);
  // What a mass curve fixes: the melt per second of the experiment.
  const double kg = fit.value("kg"), sec = fit.value("seconds_per_cycle");
  j["kg_per_second_per_cycle"] = kg / sec;
  add_solver_json(j, fit);
  j["series_comparison"] = series_comparison_json(cmp, "fitted");
  j["outputs"] = {{"curve", "mass_curve.csv"}, {"chart", "mass_curve.png"}};
  return j;
}

}  // namespace

json run_fit(const FitRunOptions& o, const std::function<void(const std::string&)>& log) {
  require(o.holdout >= 0 && o.holdout < 1, fmt::format("--holdout: must be in [0, 1) (got {})", o.holdout));
  require(o.volume_weight >= 0 && std::isfinite(o.volume_weight), "--volume-weight: must be >= 0");
  require(std::isfinite(o.first_cycle) && o.first_cycle >= 0, "--first-cycle: must be >= 0");
  RunFolder folder(o.out_dir, {"--out", "fit.json", "fit", o.overwrite});
  Provenance provenance = start_provenance("fit", o.command_line);
  const verify::ObservationSequence obs = verify::load_observations(o.observations);
  std::shared_ptr<const PreparedSimulation> prepared = prepare_simulation(o.simulation, /*check_output=*/false);
  YAML::Node kl_doc;
  const std::map<std::string, double> kl_values = kl_parameter_values(o, *prepared, kl_doc);
  if (!obs.has_photos()) {
    json j = run_series_fit(o, obs, prepared, kl_doc, kl_values, folder.path(), log);
    return commit_run(folder, std::move(j), provenance);
  }
  require(!o.mass_g, "--mass-g: the initial mass is for a mass series without photos");
  require(!o.seconds_per_cycle, "--seconds-per-cycle: photos map to cycles by --cycles-per-photo");
  const std::vector<verify::FitParameter> params = fit_parameters(o, o.simulation.kg, kl_values);

  // Frames: all, minus the held-out tail.
  const int n_frames = static_cast<int>(obs.frames.size());
  const int n_fit = std::max(1, static_cast<int>(std::floor(n_frames * (1.0 - o.holdout))));
  verify::FitOptions fo = o.fit_options;
  fo.first_cycle = o.first_cycle;
  fo.frames.clear();
  for (int k = 0; k < n_fit; ++k) fo.frames.push_back(k);
  fo.log = log;
  std::optional<verify::VolumeSeries> volume;
  if (o.volume_weight > 0) {
    volume = volume_series(obs, n_fit);
    fo.volume_weight = o.volume_weight;
  }

  EmpiricalModel model(prepared, kl_doc);
  const verify::FitResult fit = verify::fit_sequence(obs, model, params, fo, volume);
  const verify::CompareResult cmp = compare_fitted_run(obs, model, fit, o, folder.path() / "comparison", log);

  json j = fit_json(obs, o, fit, cmp, n_fit);
  provenance.timings_s.emplace_back("fit", fit.time_s);
  return commit_run(folder, std::move(j), provenance);
}

}  // namespace meltlab::experiments
