#include "melt_options.h"

#include <memory>

namespace meltlab::cli {

std::function<void()> add_melt_options(CLI::App& sub, experiments::SimulateOptions& options, const MeltOptionSet& set) {
  // Without --units the coefficients are always relative to L0: say so in their help.
  const std::string per_l0 = set.units ? "(x L0 with --units relative)" : "(x L0, the mean input edge length)";
  sub.add_option("--kg", options.kg, set.kg_help)->default_val(set.kg);
  sub.add_option("--ke", options.kE, "kE: weight of the edge vector M_E, per cycle " + per_l0)->default_val(set.kE);
  auto kn = std::make_shared<double>(0.0);
  CLI::Option* kn_opt = nullptr;
  if (set.kn) kn_opt = sub.add_option("--kn", *kn, "kN: weight of the normal vector M_N, per cycle (default kE/100)");
  sub.add_option("--kr", options.kr, "kr: minimum edge length; shorter edges collapse " + per_l0)->default_val(set.kr);
  auto units = std::make_shared<std::string>("relative");
  if (set.units)
    sub.add_option("--units", *units,
                   std::string("relative: ") + (set.kn ? "--ke/--kn/--kr" : "--ke/--kr") +
                       " are multiples of the mean input edge length L0; absolute: mesh units")
        ->check(CLI::IsMember({"relative", "absolute"}))
        ->default_val("relative");
  if (set.kl) sub.add_option("--kl", options.kl_file, set.kl_help);
  auto precision = std::make_shared<std::string>("double");
  if (set.precision)
    sub.add_option("--precision", *precision, "Floating point type of the mesh")
        ->check(CLI::IsMember({"float", "double"}))
        ->default_val("double");
  if (set.threads)
    sub.add_option("--threads", options.threads, "Worker threads (0 = all cores, 1 = serial execution)")
        ->default_val(0);

  return [&options, set, kn, kn_opt, units, precision]() {
    if (set.units) options.relative_units = *units == "relative";
    if (set.precision) options.double_precision = *precision == "double";
    if (kn_opt != nullptr && kn_opt->count() > 0) options.kN = *kn;
  };
}

}  // namespace meltlab::cli
