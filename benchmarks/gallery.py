"""The gallery: every built-in case run at its defaults, with its picture, objective and time.

    python -m benchmarks.gallery --runs DIR [--cases a,b,...] [--run] [--out docs/gallery.md]
        [--img docs/img/gallery] [--timeout 1800]

With ``--run``, each case (all of ``pacto cases`` unless ``--cases`` names some) is run at its
defaults, ``pacto run CASE --out DIR/CASE``, unless DIR/CASE/summary.json exists.  The run's
output goes to DIR/CASE/gallery_run.log; its exit code, wall time, thread count, the machine
and its load average at the start to DIR/CASE/gallery_run.json.  A run longer than
``--timeout`` seconds is stopped by SIGTERM (pacto keeps its checkpoint) and the page says so.
Then the page ``--out`` is written from each folder's summary.json, gallery_run.json and
pictures alone, and one picture per case goes to ``--img``/CASE.png: the run's design.png, and
its part.png beside it when the run made a part (the C-beam analysis: its deformed.png),
downscaled to under 150 kB.
"""
from __future__ import annotations

import argparse
import datetime
import io
import json
import os
import subprocess
import sys
import time

from PIL import Image

from benchmarks.__main__ import machine
from pacto_ng.case import available_cases
from pacto_ng.threads import thread_count

RECORD = "gallery_run.json"
LOG = "gallery_run.log"
IMG_BYTES = 150_000  # the largest picture written
TALL = 900  # px: pictures side by side are scaled to one height, this at most
MAX_WIDTH = 1400  # px: and the row to this width at most
MAX_HEIGHT = 1400  # px: pictures one above the other, to this height at most
HEIGHT = 600  # px: the height a picture of a row should keep at least ROW_SHRINK of
ROW_SHRINK = 0.7  # (else the pictures go one above the other)
GAP = 16  # px between two pictures
DASH = "—"
#: the summary table's columns: (heading, key of :func:`figures`)
COLUMNS = (("case", None), ("dim", "dim"), ("model, load", "model_load"),
           ("objective at the end", "objective"), ("output Δ", "output"),
           ("iterations", "iterations"), ("converged", "converged"), ("greyness", "greyness"),
           ("part sealed", "sealed"), ("gap", "gap"),
           ("optimisation / analysis (s)", "optimisation_s"), ("whole run (s)", "command_s"))


def builtin_cases() -> dict:
    """The built-in cases, by name, in the order of ``pacto cases``: name -> one-line summary."""
    return {c.name: c.summary for c in available_cases()}


def _tail(path: str, lines: int = 3) -> list[str]:
    """The last non-empty ``lines`` lines of the text file ``path`` (none if it is missing)."""
    if not os.path.exists(path):
        return []
    with open(path, errors="replace") as fh:
        text = [ln.rstrip() for ln in fh if ln.strip()]
    return text[-lines:]


def run_case(name: str, folder: str, timeout: float) -> dict | None:
    """``pacto run NAME --out FOLDER`` unless FOLDER/summary.json exists (None then); its record
    (command, exit code, wall time, threads, machine, the log's last lines) in FOLDER/RECORD."""
    if os.path.exists(os.path.join(folder, "summary.json")):
        return None
    os.makedirs(folder, exist_ok=True)
    # --overwrite: a folder without summary.json holds at most an unfinished run's files
    argv = [sys.executable, "-m", "pacto_ng.cli", "run", name, "--out", folder, "--overwrite"]
    record = {"command": f"pacto run {name} --out {folder}", "argv": argv[1:],
              "started": f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC",
              "threads": thread_count(), "cores": os.cpu_count(),
              "load_average": os.getloadavg()[0], "machine": machine(),
              "timeout_s": timeout, "timed_out": False}
    log = os.path.join(folder, LOG)
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        proc = subprocess.Popen(argv, stdout=fh, stderr=subprocess.STDOUT)
        try:
            code = proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            record["timed_out"] = True
            proc.terminate()  # pacto stops as on Ctrl-C: the checkpoint kept
            try:
                code = proc.wait(timeout=120)
            except subprocess.TimeoutExpired:
                proc.kill()
                code = proc.wait()
    record.update(exit_code=code, wall_s=time.perf_counter() - t0, last_lines=_tail(log))
    with open(os.path.join(folder, RECORD), "w") as fh:
        json.dump(record, fh, indent=1)
    return record


def read_run(folder: str) -> dict:
    """A run folder's summary.json, gallery record and the summary of the part's refinement
    (refine/summary.json, written after a pressure run), each None when missing."""
    out = {}
    for key, name in (("summary", "summary.json"), ("record", RECORD),
                      ("refine", os.path.join("refine", "summary.json"))):
        path = os.path.join(folder, name)
        out[key] = None
        if os.path.exists(path):
            with open(path) as fh:
                out[key] = json.load(fh)
    return out


def _num(value, fmt: str) -> str:
    return DASH if value is None else format(value, fmt)


def _seconds(value) -> str:
    return DASH if value is None else f"{value:.1f}" if value < 10 else f"{value:.0f}"


def _dimension(summary: dict) -> str:
    """'2D, 1,200 elements' from the summary's mesh (its dim, or the kind of an analysis's)."""
    mesh = summary.get("mesh") or {}
    dim = mesh.get("dim") or {"quad": 2, "trig": 2, "hex": 3, "tet": 3}.get(mesh.get("kind"))
    text = DASH if dim is None else f"{dim}D"
    if mesh.get("elements") is not None:
        text += f", {mesh['elements']:,} elements"
    return text


def _model_load(summary: dict) -> str:
    """'linear, 1e+06 Pa' (an analysis: 'neohookean, load factor up to 20')."""
    if "objective" not in summary:
        load = (summary.get("parameters") or {}).get("load")
        return f"{summary.get('model', DASH)}, load factor up to {_num(load, '.4g')}"
    text = (f"{summary.get('model', DASH)}, {_num(summary.get('load'), '.4g')} "
            f"{summary.get('load_unit', '')}").rstrip()
    reached = summary.get("load_factor_reached")
    if reached is not None and reached < 1:
        text += f" (reached {reached:.3g} of it)"
    return text


def _part(summary: dict) -> tuple[str, str]:
    """(sealed, gap) of the run's part, as the table shows them."""
    part = summary.get("part")
    if not part:
        return DASH, DASH
    if not part.get("made"):
        return "no part", DASH
    sealed = {True: "yes", False: "**no**", None: "no chamber"}[part.get("sealed")]
    gap = part.get("gap")
    return sealed, DASH if gap is None else f"{100 * gap:+.1f} %"


def _yes_no(value) -> str:
    return {True: "yes", False: "no"}.get(value, DASH)


def figures(run: dict) -> dict:
    """The figures of one run, formatted for the page, from its summary and record alone."""
    s, rec = run["summary"] or {}, run["record"] or {}
    fig = {k: DASH for _, k in COLUMNS[1:]}
    fig["command_s"] = _seconds(rec.get("wall_s"))
    if rec.get("timed_out"):
        fig["command_s"] += " (stopped: time limit)"
    elif rec.get("exit_code") not in (None, 0):
        fig["command_s"] += f" (exit code {rec['exit_code']})"
    if run["summary"] is None:
        fig["objective"] = "failed" if rec else "not run"
        return fig
    fig.update(dim=_dimension(s), model_load=_model_load(s),
               optimisation_s=_seconds(s.get("wall_time_s")))
    if "objective" not in s:  # an analysis (the C-beam): the load factor it reached
        fig.update(objective="(an analysis)",
                   output=f"load factor {_num(s.get('load_factor_reached'), '.4g')} reached")
        return fig
    sealed, gap = _part(s)
    name = s.get("objective_name", "objective")
    fig.update(objective=(f"{name} " if name != "objective" else "") + f"{s['objective']:.4g}",
               output=_num(s.get("output_displacement"), ".4g"),
               iterations=str(s.get("iterations", DASH)), converged=_yes_no(s.get("converged")),
               greyness=_num(s.get("greyness"), ".3f"), sealed=sealed, gap=gap)
    return fig


def status(run: dict, folder: str) -> str:
    """'' for a finished run, else what happened, in the run's own words."""
    rec = run["record"]
    if run["summary"] is None and rec is None:
        return f"not run: no summary.json in {folder}"
    if rec is None or rec.get("exit_code") == 0:
        return ""
    said = " / ".join(f"`{ln}`" for ln in rec.get("last_lines", [])) or "no output"
    if rec.get("timed_out"):
        head = (f"stopped by the gallery's time limit after {rec['wall_s']:.0f} s "
                f"(--timeout {rec['timeout_s']:g})")
    else:
        head = f"the run ended with exit code {rec['exit_code']} after {rec['wall_s']:.0f} s"
    kept = ("" if run["summary"] is None else
            "; the optimisation had finished (its summary.json is shown)"
            + ("; the part's refinement had not" if run.get("refine") is None
               and (run["summary"].get("part") or {}).get("made") else ""))
    return f"{head}{kept}; its last lines: {said}"


def _fit(im: Image.Image, width: int, height: int) -> Image.Image:
    scale = min(1.0, width / im.width, height / im.height)
    if scale >= 1.0:
        return im
    return im.resize((max(1, round(im.width * scale)), max(1, round(im.height * scale))),
                     Image.LANCZOS)


def _save_small(im: Image.Image, dest: str, limit: int = IMG_BYTES) -> int:
    """``im`` as a 256-colour PNG under ``limit`` bytes (shrunk by steps until it is)."""
    while True:
        buf = io.BytesIO()
        im.quantize(colors=256, dither=Image.Dither.NONE).save(buf, "PNG", optimize=True)
        if buf.tell() <= limit or im.width < 200:
            break
        im = _fit(im, int(im.width * 0.85), int(im.height * 0.85))
    with open(dest, "wb") as fh:
        fh.write(buf.getvalue())
    return buf.tell()


def _combine(images: list) -> tuple[Image.Image, str]:
    """The pictures side by side at one height (TALL at most, the row MAX_WIDTH at most), or
    one above the other at one width when a picture of the row would be shown at less than
    ROW_SHRINK of its size at HEIGHT (wide 3D pictures); the result and 'beside' or 'above'.
    No picture is enlarged."""
    gaps = GAP * (len(images) - 1)
    h = min(TALL, *(im.height for im in images))
    row = sum(im.width * h / im.height for im in images)
    h = max(1, int(h * min(1.0, (MAX_WIDTH - gaps) / row)))
    beside = len(images) == 1 or all(h / im.height >= ROW_SHRINK * min(1.0, HEIGHT / im.height)
                                     for im in images)
    if beside:
        images = [im.resize((max(1, round(im.width * h / im.height)), h), Image.LANCZOS)
                  for im in images]
        size = (sum(im.width for im in images) + gaps, h)
    else:
        w = min(MAX_WIDTH, *(im.width for im in images))
        images = [im.resize((w, max(1, round(im.height * w / im.width))), Image.LANCZOS)
                  for im in images]
        size = (w, sum(im.height for im in images) + gaps)
    out = Image.new("RGB", size, "white")
    at = 0
    for im in images:
        out.paste(im, (at, 0) if beside else (0, at))
        at += (im.width if beside else im.height) + GAP
    return _fit(out, MAX_WIDTH, MAX_HEIGHT), "beside" if beside else "above"


def picture(folder: str, dest: str) -> str | None:
    """The case's picture in ``dest``: design.png, with part.png beside it (or below it) when
    both exist (deformed.png for an analysis); what it shows, or None without any."""
    names = [n for n in ("design.png", "part.png") if os.path.exists(os.path.join(folder, n))]
    if "design.png" not in names:
        names = ["deformed.png"] if os.path.exists(os.path.join(folder, "deformed.png")) else []
    if not names:
        if os.path.exists(dest):  # an earlier run's picture: not this run's
            os.remove(dest)
        return None
    images = []
    for n in names:
        with Image.open(os.path.join(folder, n)) as im:
            images.append(im.convert("RGB"))
    combined, how = _combine(images)
    os.makedirs(os.path.dirname(dest) or ".", exist_ok=True)
    _save_small(combined, dest)
    if len(names) == 1:
        return names[0]
    return f"{names[0]} ({'left' if how == 'beside' else 'top'}) and {names[1]}"


def table(rows: list) -> str:
    """The summary table: one line per case (name, figures)."""
    lines = ["| " + " | ".join(c for c, _ in COLUMNS) + " |",
             "|" + "---|" * len(COLUMNS)]
    for name, fig in rows:
        cells = [f"[{name}](#{name})"] + [fig[k] for _, k in COLUMNS[1:]]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _times(s: dict, rec: dict, refine: dict | None, what: str) -> str:
    """'- wall time: ...' from the summary's and the record's times."""
    part = (s.get("part") or {}).get("wall_time_s")
    text = f"- wall time: {_seconds(s.get('wall_time_s'))} s {what}"
    if part is not None:
        text += f", {_seconds(part)} s part"
    if refine is not None and refine.get("wall_time_s") is not None:
        text += f", {_seconds(refine['wall_time_s'])} s refinement"
    if rec:
        n = rec["threads"]
        text += (f"; {_seconds(rec.get('wall_s'))} s the whole `pacto run` ({n} thread"
                 f"{'s' if n > 1 else ''}, load average {rec['load_average']:.1f} at its "
                 f"start, {rec['started']})")
    return text


def _figure_lines(s: dict, fig: dict) -> list:
    """The entry's list of figures (an optimisation's or an analysis's)."""
    lines = [f"- dimension: {fig['dim']}", f"- model and load: {fig['model_load']}"]
    if "objective" not in s:
        return lines + [f"- an analysis, no optimisation: {fig['output']} "
                        f"({s.get('stopped_because', DASH)})"]
    stop = s.get("message") or s.get("stopped") or DASH
    part = s.get("part") or {}
    part_line = ("not made: " + str(part.get("why", DASH)) if part and not part.get("made")
                 else f"sealed: {fig['sealed']}; gap: {fig['gap']}" if part else DASH)
    return lines + [
        f"- objective at the end: {fig['objective']}; output displacement Δ: {fig['output']}",
        f"- iterations: {fig['iterations']}; converged: {fig['converged']} ({stop})",
        f"- greyness: {fig['greyness']}; volume fraction: "
        f"{_num(s.get('volume_fraction'), '.3f')}",
        f"- part: {part_line}"]


def _refined(r: dict) -> str:
    """The line of the part's refinement (refine/summary.json)."""
    unit = (r.get("units") or {}).get("delta", "")
    text = (f"- refined part (refine/summary.json): Δ {_num(r.get('delta_before'), '.4g')} → "
            f"{_num(r.get('delta_after'), '.4g')} {unit}".rstrip())
    if r.get("gain") is not None:
        text += f" ({100 * r['gain']:+.1f} %)"
    if r.get("gap") is not None:
        text += f", {100 * r['gap']:+.1f} % from the design's Δ"
    return text + (f"; status {r.get('status', DASH)}, sealed: {_yes_no(r.get('sealed'))}")


def section(name: str, summary_line: str, run: dict, fig: dict, folder: str,
            img: str | None, shown: str | None) -> str:
    """One case's entry: name, description, what went wrong if anything, picture, figures."""
    s, rec = run["summary"] or {}, run["record"] or {}
    out = [f"### {name}", "", f"*{summary_line}*", ""]
    said = status(run, folder)
    if said:
        out += [f"**{said}**", ""]
    if img is not None:
        out += [f"![{name}: {shown}]({img})", "", f"Picture: the run's {shown}.", ""]
    if run["summary"] is None:
        return "\n".join(out) + "\n"
    out += _figure_lines(s, fig)
    if run.get("refine"):
        out.append(_refined(run["refine"]))
    out.append(_times(s, rec, run.get("refine"), "optimisation" if "objective" in s else
                      "analysis"))
    return "\n".join(out) + "\n"


def intro(runs: dict, command: str) -> str:
    """The page's head: what an entry shows, the machine, the threads and the command."""
    recs = [r["record"] for r in runs.values() if r["record"]]
    threads = sorted({r["threads"] for r in recs})
    total = sum(r["wall_s"] for r in recs)
    machine = (f"Machine and software, as recorded at the first run "
               f"({recs[0]['command'].split()[2]}): {recs[0]['machine']}.  NGSolve threads "
               f"of the runs (`PACTO_THREADS`): {', '.join(map(str, threads))}; "
               f"{len(recs)} runs, {total:.0f} s in all (each entry gives the load average "
               f"at its run's start)."
               if recs else "No run folder holds a gallery record: the machine is unknown.")
    return "\n".join([
        "# Gallery of the built-in cases", "",
        "Every built-in case (`pacto cases`) run at its defaults: `pacto run CASE`.  An entry "
        "shows the case's one-line description, the run's picture and the figures of its "
        "summary.json.  The picture: design.png, the filtered density ρ̄ of the design "
        "(mirrored where the case is half of a symmetric domain; in 3D the ρ̄ = 0.5 "
        "iso-surface and a cut), and where the run made a part, part.png: the thresholded "
        "part deformed at the run's load, true scale, over its undeformed outline.  The "
        "figures: dimension and mesh, model and load, the objective and the output "
        "displacement Δ at the end (summary `output_displacement`: along the output port for "
        "mechanisms, at the load for compliance cases), the iterations, whether the run "
        "converged or stopped at its iteration cap, the greyness (Sigmund's measure "
        "4 ρ̄ (1 − ρ̄) averaged over the domain: 0 for a solid-void design), whether the part "
        "holds pressure (`sealed`; *no chamber* without a pressure load), its gap "
        "(Δ_part − Δ_design)/|Δ_design| (the part and the design analysed at the same "
        "order), where the run refined its part (refine/summary.json) the part's Δ before "
        "and after the refinement, and the wall times: the optimisation (summary "
        "`wall_time_s`), the part (`part.wall_time_s`), the refinement and the whole "
        "`pacto run` command as timed by the page's runner.  Every figure is read from the "
        "run folders.", "",
        machine, "",
        f"Regenerate (`--run` runs only the cases whose folder has no summary.json; without "
        f"it the page is rebuilt from the folders as they are): `{command}`", ""])


def build(runs_dir: str, names: list, out: str, img_dir: str, command: str) -> str:
    """Write the page ``out`` and the pictures in ``img_dir`` from the run folders."""
    cases = builtin_cases()
    runs = {n: read_run(os.path.join(runs_dir, n)) for n in names}
    rows, parts = [], []
    for name in names:
        folder = os.path.join(runs_dir, name)
        fig = figures(runs[name])
        dest = os.path.join(img_dir, f"{name}.png")
        shown = picture(folder, dest)
        rel = (os.path.relpath(dest, os.path.dirname(os.path.abspath(out))) if shown else None)
        rows.append((name, fig))
        parts.append(section(name, cases.get(name, "(not a built-in case)"), runs[name], fig,
                             folder, rel, shown))
    text = "\n".join([intro(runs, command), "## The figures", "", table(rows), "",
                      "## The cases", "", *parts])
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as fh:
        fh.write(text)
    return text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.gallery",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--runs", required=True, help="the folder of the run folders (DIR/CASE)")
    ap.add_argument("--cases", default=None, help="a,b,...: these cases (default: all)")
    ap.add_argument("--run", action="store_true", help="run the cases without a summary.json")
    ap.add_argument("--out", default=os.path.join("docs", "gallery.md"))
    ap.add_argument("--img", default=os.path.join("docs", "img", "gallery"))
    ap.add_argument("--timeout", type=float, default=1800.0,
                    help="seconds after which a run is stopped (default 1800)")
    a = ap.parse_args(argv)
    known = list(builtin_cases())
    names = known if a.cases is None else [n.strip() for n in a.cases.split(",") if n.strip()]
    unknown = [n for n in names if n not in known]
    if unknown:
        ap.error(f"unknown case(s) {', '.join(unknown)} (built-in: {', '.join(known)})")
    if a.run:
        for name in names:
            rec = run_case(name, os.path.join(a.runs, name), a.timeout)
            print(f"[{name}] " + ("kept (summary.json exists)" if rec is None else
                                  f"exit code {rec['exit_code']}, {rec['wall_s']:.0f} s"),
                  flush=True)
    threads = os.environ.get("PACTO_THREADS")
    command = " ".join([f"PACTO_THREADS={threads}"] * (threads is not None)
                       + ["python -m benchmarks.gallery", f"--runs {a.runs}"]
                       + [f"--cases {a.cases}"] * (a.cases is not None) + ["--run"])
    build(a.runs, names, a.out, a.img, command)
    print(f"wrote {a.out} and {len(names)} pictures in {a.img}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
