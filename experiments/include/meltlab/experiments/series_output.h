#pragma once
// The outputs of a weighing experiment, shared by `meltlab fit` (a mass series alone) and
// `meltlab predict`: the series and a model's curve against it as JSON, the per-reading CSV
// and the chart (verify/mass_series.h computes them; they are written here, at the edge).

#include <meltlab/verify/mass_series.h>
#include <meltlab/verify/observations.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>

namespace meltlab::experiments {

/// Reads and checks the manifest's series (verify::check_melt_series). Throws InputError.
verify::MeltSeries load_melt_series(const verify::ObservationSequence& observations, double density_kg_m3);

/// The ice at t = 0: `mass_g` if given, else the reading at t = 0; InputError naming the
/// file (and --mass-g) when there is none. `from` receives where it came from.
double initial_mass_g(const verify::MeltSeries& series, const std::optional<double>& mass_g, std::string& from);

/// {file, file_hash, quantity, rows, used, left_out: [...], noise_g, tolerance_g, density_kg_m3}
nlohmann::json series_json(const verify::MeltSeries& series);

/// {samples, rmse_g, max_abs_error_g, max_error_time_s, mean_error_g, initial_g,
///  half_mass_time_s: {observed, <model>}, time_to_melt_s: {observed, <model>, level_g}}
nlohmann::json series_comparison_json(const verify::SeriesComparison& c, const std::string& model);

/// DIR/<name>: time_s, observed_g, <model>_g, used (1, or 0 for readings left out) per row of
/// the file, in time order; atomically.
void write_mass_curve_csv(const std::filesystem::path& file, const verify::MeltSeries& series,
                          const verify::MassCurve& model, const std::string& model_name);

}  // namespace meltlab::experiments
