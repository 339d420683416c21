"""One module per kind of `meltlab reproduce` experiment report; each has a function of the kind's name,
(exp_dir, args) -> None, that writes EXP_DIR/report.json."""
