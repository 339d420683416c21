#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>
#include <meltlab/experiments/series_output.h>

#include <fmt/format.h>

#include <cmath>
#include <sstream>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

verify::MeltSeries load_melt_series(const verify::ObservationSequence& obs, double density_kg_m3) {
  if (!obs.mass_series) throw InputError(fmt::format("{}: names no mass_series", obs.manifest.string()));
  verify::MeltSeriesOptions mo;
  mo.density_kg_m3 = density_kg_m3;
  return verify::check_melt_series(verify::read_time_series(*obs.mass_series), mo);
}

double initial_mass_g(const verify::MeltSeries& s, const std::optional<double>& mass_g, std::string& from) {
  if (mass_g) {
    if (!(std::isfinite(*mass_g) && *mass_g > 0))
      throw InputError(fmt::format("--mass-g: must be a number > 0 (got {})", *mass_g));
    from = "--mass-g";
    return *mass_g;
  }
  if (s.time_s.front() != 0)
    throw InputError(
        fmt::format("{}:{}: the first reading is at t = {} s, not 0: give the mass of the ice at t = 0 "
                    "with --mass-g",
                    s.file.string(), s.line.front(), s.time_s.front()));
  from = fmt::format("the reading at t = 0 ({}:{})", s.file.filename().string(), s.line.front());
  return s.mass_g.front();
}

json series_json(const verify::MeltSeries& s) {
  return {{"file", fs::absolute(s.file).string()},
          {"file_hash", file_hash(s.file)},
          {"quantity", s.quantity},
          {"rows", s.rows},
          {"used", s.time_s.size()},
          {"left_out", s.left_out},
          {"noise_g", s.noise_g},
          {"tolerance_g", s.tolerance_g},
          {"density_kg_m3", s.density_kg_m3}};
}

json series_comparison_json(const verify::SeriesComparison& c, const std::string& model) {
  auto opt = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  return {{"samples", c.samples},
          {"rmse_g", c.rmse_g},
          {"max_abs_error_g", c.max_abs_error_g},
          {"max_error_time_s", c.max_error_time_s},
          {"mean_error_g", c.mean_error_g},
          {"initial_g", c.initial_g},
          {"half_mass_time_s",
           {{"observed", opt(c.half_mass_time_observed_s)}, {model, opt(c.half_mass_time_predicted_s)}}},
          {"time_to_melt_s",
           {{"observed", opt(c.time_to_melt_observed_s)},
            {model, opt(c.time_to_melt_predicted_s)},
            {"level_g", c.melted_fraction * c.initial_g}}}};
}

void write_mass_curve_csv(const fs::path& file, const verify::MeltSeries& s, const verify::MassCurve& model,
                          const std::string& model_name) {
  struct Row {
    double t, g;
    bool used;
  };
  std::vector<Row> rows;
  for (std::size_t i = 0; i < s.time_s.size(); ++i) rows.push_back({s.time_s[i], s.mass_g[i], true});
  for (std::size_t i = 0; i < s.left_out_readings.time_s.size(); ++i)
    rows.push_back({s.left_out_readings.time_s[i], s.left_out_readings.mass_g[i], false});
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.t < b.t; });
  std::ostringstream out;
  out << "time_s,observed_g," << model_name << "_g,used\n";
  for (const Row& r : rows)
    out << fmt::format("{},{:.9g},{:.9g},{}\n", r.t, r.g, verify::mass_at(model, r.t), r.used ? 1 : 0);
  write_text_atomically(file, out.str());
}

}  // namespace meltlab::experiments
