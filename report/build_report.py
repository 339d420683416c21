#!/usr/bin/python3
"""Builds the HTML report of a `meltlab reproduce` output folder.

usage: build_report.py OUT_DIR
Reads OUT_DIR/summary.json (what ran, was reused or failed) and each experiment's
report.json fragment (written by report/experiment_report.py), copies every figure (PNG)
and every table and figure data file (CSV) into OUT_DIR/report/<experiment>/ and writes
OUT_DIR/report/index.html: the hardware of this machine and of the monograph, the run
summary, the chapter 8 P1/P100 table over all molds, and per experiment its tables (the
harness's numbers beside the source's), figures and a line on what matches.
The report folder is self-contained (relative links only).
"""
import csv
import html
import json
import os
import platform
import shutil
import sys
from pathlib import Path

MAX_ROWS = 60  # longer CSVs are linked, and their first rows shown


def cpu_info():
    model, n, mhz = "unknown", 0, None
    try:
        for line in open("/proc/cpuinfo"):
            k, _, v = line.partition(":")
            k, v = k.strip(), v.strip()
            if k == "model name":
                model = v
                n += 1
            elif k == "cpu MHz" and mhz is None:
                mhz = v
    except OSError:
        pass
    mem = None
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal:"):
                mem = int(line.split()[1]) / 1024 / 1024
    except OSError:
        pass
    return {"CPU": model, "logical CPUs": str(n or os.cpu_count()), "clock now (MHz)": mhz or "?",
            "memory (GiB)": f"{mem:.1f}" if mem else "?", "kernel": platform.release(),
            "python": platform.python_version()}


def read_csv(path: Path):
    with open(path, newline="") as f:
        return list(csv.reader(f))


def write_csv(path: Path, rows):
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows)


def table_html(rows, link):
    if not rows:
        return "<p class=warn>empty table</p>"
    head, body = rows[0], rows[1:]
    out = ["<table><thead><tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in head) + "</tr></thead><tbody>"]
    for r in body[:MAX_ROWS]:
        out.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>")
    out.append("</tbody></table>")
    note = f" (first {MAX_ROWS} of {len(body)} rows)" if len(body) > MAX_ROWS else ""
    out.append(f'<p class=small><a href="{html.escape(link)}">CSV</a>{note}</p>')
    return "\n".join(out)


def copy_into(src_root: Path, rel: str, dst_root: Path):
    src = src_root / rel
    dst = dst_root / rel
    dst.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(src, dst)
    return dst


def experiment_section(e, out: Path, rep: Path):
    """One experiment's section: its tables and figures copied into rep/<name>/, or the
    failure with the tails of its logs. Returns (section HTML, contents line, report.json
    fragment or None)."""
    name = e["name"]
    exp = out / e["folder"]
    dst = rep / name
    dst.mkdir(parents=True, exist_ok=True)
    parts = [f'<section id="{html.escape(name)}"><h2>{html.escape(e["title"])}</h2>',
             f"<p class=small>experiment <code>{html.escape(name)}</code> · reproduces "
             f"{html.escape(', '.join(e['sources']))} · status <b>{html.escape(e['status'])}</b> · config "
             f"<code>{html.escape(os.path.relpath(e['config'], Path(__file__).resolve().parent.parent))}</code></p>"]
    frag_path = exp / "report.json"
    if e["status"] not in ("ran", "reused", "kept") or not frag_path.is_file():
        msg = e["error"] or "no report.json"
        parts.append(f"<p class=bad>FAILED: {html.escape(msg)}</p>")
        for log in sorted((exp / "logs").glob("*.err")) if (exp / "logs").is_dir() else []:
            if log.stat().st_size:
                tail = log.read_text(errors="replace").splitlines()[-5:]
                parts.append(f"<p class=small>{html.escape(log.name)}:</p><pre>{html.escape(chr(10).join(tail))}</pre>")
        toc = f'<li><a href="#{html.escape(name)}">{html.escape(e["title"])}</a> <span class=bad>failed</span></li>'
        return "\n".join(parts) + "</section>", toc, None
    frag = json.loads(frag_path.read_text())
    m = frag.get("matches")
    badge = {True: "<span class=ok>matches</span>", False: "<span class=bad>does not match</span>",
             None: "<span class=qual>qualitative</span>"}[m]
    parts.append(f"<p class=verdict>{badge} {html.escape(frag['verdict'])}</p>")
    parts.append(f"<p class=small>hardware: this machine (see top) · the source: "
                 f"{html.escape(frag.get('source_hardware', 'not stated'))}</p>")
    for t in frag.get("tables", []):
        copy_into(exp, t["csv"], dst)
        parts.append(f"<h3>{html.escape(t['caption'])}</h3>")
        parts.append(table_html(read_csv(exp / t["csv"]), f"{name}/{t['csv']}"))
    for fg in frag.get("figures", []):
        copy_into(exp, fg["png"], dst)
        data = ""
        if fg.get("data") and (exp / fg["data"]).is_file():
            copy_into(exp, fg["data"], dst)
            data = f' · <a href="{html.escape(name + "/" + fg["data"])}">data (CSV)</a>'
        parts.append(f'<figure><img src="{html.escape(name + "/" + fg["png"])}" alt="{html.escape(fg["caption"])}">'
                     f"<figcaption>{html.escape(fg['caption'])}{data}</figcaption></figure>")
    toc = f'<li><a href="#{html.escape(name)}">{html.escape(e["title"])}</a> {badge}</li>'
    return "\n".join(parts) + "</section>", toc, frag


def chapter8_section(p_rows, rep: Path):
    """Chapter 8 over all molds: the P1/P100 table and the ordering claim of spec §9.5."""
    mono = {"giraffe": (0.068818, 0.137467), "airplane": (0.027969, 0.10399),
            "ship": (0.044926, 0.120915), "warship": (0.07131, 0.178187)}
    rows = [["mold", "P1 meltlab (kg right)", "P1 monograph", "P100 meltlab (kg right)", "P100 monograph",
             "P max meltlab", "P100 <= 0.2 meltlab"]]
    for mold, p1, p100, pmax in p_rows:
        rows.append([mold, f"{p1:.4f}", mono[mold][0], f"{p100:.4f}", mono[mold][1], f"{pmax:.4f}",
                     "yes" if p100 <= 0.2 else "no"])
    write_csv(rep / "p1_p100_all.csv", rows)
    order1 = [r[0] for r in sorted(p_rows, key=lambda r: r[1])]
    order100 = [r[0] for r in sorted(p_rows, key=lambda r: r[2])]
    mono1 = [k for k, _ in sorted(mono.items(), key=lambda kv: kv[1][0]) if k in order1]
    return ("<section id=p1p100><h2>Chapter 8: P1 and P100 of the molds (spec §9.5)</h2>"
            + table_html(rows, "p1_p100_all.csv")
            + f"<p class=verdict>P1 order meltlab {' < '.join(order1)}; P100 order {' < '.join(order100)}; "
              f"monograph P1 = P100 order {' < '.join(mono1)}. "
            + ("Same order of P1 and P100, as in the monograph. " if order1 == order100 else
               "The order of P100 differs from that of P1 (the monograph's were equal). ")
            + "The inverse-crime photos carry no mold, scan or optics error, so the harness's P values are "
              "smaller than the monograph's and their order is not expected to follow it.</p></section>")


def page_head(summary, hw_rows, srows, toc, problems):
    """The top of index.html: style, the run, contents, hardware, run summary."""
    n = {s: sum(1 for e in summary["experiments"] if e["status"] == s)
         for s in ("ran", "reused", "failed", "not run", "kept")}
    return f"""<!doctype html><html lang=en><head><meta charset=utf-8>
<title>meltlab reproduction report</title>
<style>
body {{ font-family: sans-serif; max-width: 1100px; margin: 1em auto; padding: 0 1em; color: #222; }}
table {{ border-collapse: collapse; margin: .5em 0; font-size: 13px; }}
td, th {{ border: 1px solid #bbb; padding: 2px 6px; text-align: left; }}
th {{ background: #eee; }}
figure {{ display: inline-block; margin: .5em; max-width: 100%; vertical-align: top; }}
img {{ max-width: 520px; border: 1px solid #ddd; }}
img[src*="/overlays/"] {{ max-width: 250px; }}
figcaption, .small {{ font-size: 12px; color: #555; }}
.ok {{ background: #cfc; padding: 0 4px; }} .bad {{ background: #fcc; padding: 0 4px; }}
.qual {{ background: #ddf; padding: 0 4px; }} .verdict {{ margin: .4em 0; }}
pre {{ background: #f6f6f6; font-size: 12px; overflow-x: auto; }}
section {{ border-top: 2px solid #ccc; margin-top: 1.5em; }}
</style></head><body>
<h1>meltlab reproduction report</h1>
<p>meltlab {html.escape(summary['meltlab']['version'])} ({html.escape(summary['meltlab']['git_revision'])}),
{html.escape(summary['mode'])} mode, {summary['jobs']} parallel job(s), finished {html.escape(summary['finished'])},
{summary['seconds']:.1f} s. Experiments: {n['ran']} ran, {n['reused']} reused, {n['failed'] + n['not run']} failed
(and {n['kept']} not selected this time, kept from earlier runs).
Sources' numbers: <code>spec/melting-monograph.md</code>.</p>
<h2>Contents</h2><ul>{''.join(toc)}</ul>
<h2>Hardware</h2>{table_html(hw_rows, 'hardware_both.csv')}
<h2>Run summary</h2>{table_html(srows, 'summary.csv')}
<p>{'Experiments whose numbers do not match the source: ' + html.escape(', '.join(problems)) if problems
      else 'No quantitative mismatch flagged.'}</p>
"""


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = Path(argv[1])
    summary = json.loads((out / "summary.json").read_text())
    rep = out / "report"
    if rep.exists():
        shutil.rmtree(rep)
    rep.mkdir(parents=True)

    hw = cpu_info()
    write_csv(rep / "hardware.csv", [["field", "value"]] + [[k, v] for k, v in hw.items()])
    srows = [["experiment", "title", "status", "seconds (this run)", "seconds (run that made it)", "steps", "error"]]
    for e in summary["experiments"]:
        srows.append([e["name"], e["title"], e["status"], f"{e['seconds']:.1f}", f"{e['original_seconds']:.1f}",
                      " ".join(f"{s['name']}={s['seconds']:.1f}s" for s in e["steps"]), e["error"]])
    write_csv(rep / "summary.csv", srows)

    # One section per experiment; the chapter 8 molds' P values collected on the way.
    sections, p_rows, problems, toc = [], [], [], []
    for e in summary["experiments"]:
        section, toc_line, frag = experiment_section(e, out, rep)
        sections.append(section)
        toc.append(toc_line)
        if frag is None:
            continue
        extra = frag.get("extra", {})
        if "mold" in extra:
            p = extra["p"]
            right = next((v for k, v in p.items() if k.endswith("_kg1")), None)
            if right:
                p_rows.append([extra["mold"], right["P1"], right["P100"], right["P_max"]])
        if frag.get("matches") is False:
            problems.append(e["name"])

    ch8 = chapter8_section(p_rows, rep) if p_rows else ""
    if ch8:
        toc.insert(0, '<li><a href="#p1p100">Chapter 8: P1 and P100 of the molds</a></li>')
    hw_rows = [["", "this machine", "the monograph"],
               ["CPU", hw["CPU"] + f" ({hw['logical CPUs']} logical CPUs)", "Intel Core 2 Duo P8400, 2.26 GHz, 1066 MHz FSB"],
               ["GPU", "none used (CPU only)", "nVidia GeForce 9600M GT (melt, ch. 5); GeForce 6800GT (ice rendering, ch. 6)"],
               ["memory", hw["memory (GiB)"] + " GiB", "not stated"],
               ["photos", "generated (synth-sequence), see chapter 8 experiments", "Nikon Coolpix 995, 2048x1536, every 40 s"]]
    write_csv(rep / "hardware_both.csv", hw_rows)
    doc = page_head(summary, hw_rows, srows, toc, problems) + ch8 + "\n".join(sections) + "\n</body></html>\n"
    tmp = rep / "index.html.partial"
    tmp.write_text(doc)
    os.replace(tmp, rep / "index.html")
    print(rep / "index.html")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
