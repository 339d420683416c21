#!/usr/bin/python3
"""The report step of each `meltlab reproduce` experiment: reads the experiment's result
files, writes the numbers as CSV (the harness's beside the source's), draws what the
earlier steps did not, and writes EXP_DIR/report.json, the fragment that
report/build_report.py puts into the HTML report.

usage: experiment_report.py KIND EXP_DIR [ARGS...]
KIND: tab_2_3 | cycle_time CYCLES | deform_variants | split | kl_field | chapter8 MOLD | fit | fit_coverage |
      physics_fit MOLD |
      melt_away | liquid_figure | melt_scene | texture_filter FACTOR | stress_summary |
      module_studies | runs (generic: every simulate run folder in EXP_DIR) | vlr_seed000 | clv_seed001 | fog_seed002 | slicing_seed003 |
      sweep (meltlab sweep)

report.json: {"tables": [{"caption", "csv"}], "figures": [{"caption", "png", "data"}],
"verdict": str, "matches": bool|null, "notes": [str], "source_hardware": str, "extra": {...}}
(paths relative to EXP_DIR). The numbers the monograph reports are quoted from the spec
(spec/melting-monograph.md), section given in each table's caption.
"""
import importlib
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

KINDS = ("tab_2_3", "cycle_time", "deform_variants", "split", "kl_field", "chapter8", "fit", "fit_coverage", "physics_fit", "melt_away", "liquid_figure", "melt_scene", "texture_filter", "stress_summary", "module_studies", "runs", "vlr_seed000", "clv_seed001", "fog_seed002", "slicing_seed003", "sweep")


def main(argv):
    if len(argv) < 3 or argv[1] not in KINDS:
        print(__doc__, file=sys.stderr)
        return 2
    module = importlib.import_module(f"experiments.{argv[1]}")
    getattr(module, argv[1])(Path(argv[2]), argv[3:])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
