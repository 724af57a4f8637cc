"""report.html: the sweep report as one self-contained page (report.py writes it beside report.md).

Everything is inside the file: figures and receiver maps as PNG data URIs, the style and a small script;
no network, no CDN. Per scene: the time-vs-error figure, a sortable table of the runs (each run's
parameters on hover), and an image comparison of the truth against each method's chosen run: a wipe
slider between them, a method - truth difference view, and linear or log exposure (pre-rendered with the
same colour scale for truth and method).

Opening the page with `#selftest` makes its script move every slider and check that the shown image
changed, then write "selftest: ok" (or what failed) into the page's title: tests/report_html_browser.sh
checks it in headless Chromium.
"""
import base64
import html
import io
import json
import math
import os

import numpy as np

from figures import chosen_receiver_maps, irradiance_cmap

STYLE = """
body { font-family: sans-serif; margin: 1.5em; max-width: 1200px; }
table { border-collapse: collapse; font-size: 0.85em; }
th, td { border: 1px solid #ccc; padding: 2px 6px; text-align: right; }
th { cursor: pointer; background: #eee; }
td.text { text-align: left; }
.compare { position: relative; display: inline-block; }
.compare img { display: block; width: 384px; image-rendering: pixelated; }
.compare .top { position: absolute; top: 0; left: 0; }
.controls { margin: 0.4em 0; }
figure img { max-width: 100%; }
"""

SCRIPT = """
function sortTable(th) {
  const table = th.closest('table'), body = table.tBodies[0];
  const col = Array.from(th.parentNode.children).indexOf(th);
  const asc = th.dataset.dir !== 'asc';
  th.dataset.dir = asc ? 'asc' : 'desc';
  const key = r => { const t = r.children[col].textContent; const v = parseFloat(t); return isNaN(v) ? t : v; };
  const rows = Array.from(body.rows).sort((a, b) => {
    const x = key(a), y = key(b);
    return (x < y ? -1 : x > y ? 1 : 0) * (asc ? 1 : -1);
  });
  rows.forEach(r => body.appendChild(r));
}
function show(box) {
  const run = box.querySelector('select.run').value, exposure = box.querySelector('select.exposure').value;
  const diff = box.querySelector('input.diff').checked, wipe = box.querySelector('input.wipe').value;
  const data = JSON.parse(box.dataset.images);
  const base = box.querySelector('img.base'), top = box.querySelector('img.top');
  base.src = data.truth[exposure];
  top.src = diff ? data.runs[run].diff : data.runs[run][exposure];
  top.style.clipPath = diff ? 'none' : 'inset(0 0 0 ' + wipe + '%)';
  box.querySelector('.caption').textContent = diff ? data.runs[run].title + ': method - truth'
      : 'left of the line: truth; right: ' + data.runs[run].title;
}
function selftest() {
  const boxes = document.querySelectorAll('.imagebox');
  let ok = boxes.length > 0, why = boxes.length ? '' : 'no image comparison';
  boxes.forEach(box => {
    const top = box.querySelector('img.top'), wipe = box.querySelector('input.wipe');
    wipe.value = 10; wipe.dispatchEvent(new Event('input'));
    const a = top.style.clipPath;
    wipe.value = 90; wipe.dispatchEvent(new Event('input'));
    if (a === top.style.clipPath) { ok = false; why = 'the slider did not move the wipe'; }
    const diff = box.querySelector('input.diff'), before = top.src;
    diff.checked = true; diff.dispatchEvent(new Event('change'));
    if (top.src === before) { ok = false; why = 'the difference view did not change the image'; }
  });
  const images = Array.from(document.querySelectorAll('img'));
  const finish = tries => {
    if (images.some(img => !img.complete) && tries > 0) return setTimeout(() => finish(tries - 1), 100);
    if (images.some(img => !img.complete || img.naturalWidth === 0)) { ok = false; why = 'an image did not decode'; }
    document.title = ok ? 'selftest: ok (' + images.length + ' images)' : 'selftest: failed: ' + why;
  };
  finish(50);
}
window.addEventListener('load', () => {
  document.querySelectorAll('.imagebox').forEach(box => {
    box.querySelectorAll('select, input').forEach(el => {
      el.addEventListener('input', () => show(box));
      el.addEventListener('change', () => show(box));
    });
    show(box);
  });
  document.querySelectorAll('th').forEach(th => th.addEventListener('click', () => sortTable(th)));
  if (location.hash === '#selftest') setTimeout(selftest, 50);
});
"""


def bold(markdown_text):
    """Escaped text with Markdown's **...** as <strong> (the context line's warning)."""
    pieces = html.escape(markdown_text).split("**")
    return "".join(f"<strong>{p}</strong>" if i % 2 else p for i, p in enumerate(pieces))


def png_uri(data):
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


def file_uri(path):
    with open(path, "rb") as f:
        return png_uri(f.read())


def map_png(image, norm, cmap):
    """A 2-D map through a colour scale as PNG bytes (origin at the bottom, as the report's figures)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rgba = cmap(norm(np.flipud(np.nan_to_num(image, nan=0.0))))
    buf = io.BytesIO()
    plt.imsave(buf, rgba, format="png")
    return buf.getvalue()


def image_comparison(frame, scene, sweep_dir, chosen):
    """The comparison block of a scene (None where the sweep has no truth map or run maps)."""
    from matplotlib import colors

    c = chosen_receiver_maps(frame, scene, sweep_dir, chosen)
    if c is None:
        return None
    truth, maps, diffs, limit = c["truth"], c["maps"], c["diffs"], c["limit"]
    top = float(np.percentile(truth, 99.9)) or 1.0
    positive = truth[truth > 0]
    floor = float(np.percentile(positive, 1)) if positive.size else top * 1e-3
    scales = {"linear": colors.Normalize(0.0, top, clip=True),
              "log": colors.LogNorm(max(floor, top * 1e-4), top, clip=True)}
    cmap = irradiance_cmap()
    data = {"truth": {k: png_uri(map_png(np.maximum(truth, 1e-30), n, cmap)) for k, n in scales.items()}, "runs": {}}
    diff_norm = colors.Normalize(-limit, limit, clip=True)
    import matplotlib

    diff_cmap = matplotlib.colormaps["RdBu_r"]
    options = []
    for (p, m), d in zip(maps, diffs):
        title = f"{p['label']}, {p['frame_ms']:.2f} ms, error {p['error']:.3g}"
        entry = {k: png_uri(map_png(np.maximum(m, 1e-30), n, cmap)) for k, n in scales.items()}
        entry["diff"] = png_uri(map_png(d, diff_norm, diff_cmap))
        entry["title"] = title
        data["runs"][p["run_id"]] = entry
        options.append(f'<option value="{html.escape(p["run_id"])}">{html.escape(title)}</option>')
    return (f'<div class="imagebox" data-images="{html.escape(json.dumps(data))}">'
            f'<div class="controls">run <select class="run">{"".join(options)}</select> '
            'exposure <select class="exposure"><option value="linear">linear</option>'
            '<option value="log">log</option></select> '
            '<label><input type="checkbox" class="diff"> difference</label> '
            'wipe <input type="range" class="wipe" min="0" max="100" value="50"></div>'
            '<div class="compare"><img class="base" alt="truth"><img class="top" alt="method"></div>'
            f'<div class="caption"></div><div>Difference scale: +-{limit:.3g} W/m^2 (blue below the truth, red '
            'above).</div></div>')


def _cell(value, digits=4):
    if isinstance(value, (float, np.floating)):
        return "-" if not math.isfinite(value) else f"{value:.{digits}g}"
    return html.escape(str(value))


def runs_table(frame, scene):
    runs = frame[frame["scene"] == scene]
    if runs.empty:
        return ""
    params = [c for c in runs.columns if c.startswith("param.") and runs[c].nunique(dropna=True) > 1]
    head = "".join(f"<th>{html.escape(h)}</th>" for h in
                   ["method", *[c[6:] for c in params], "frame ms", "error", "baseline", "status"])
    rows = []
    for row in runs.to_dict("records"):
        all_params = {c[6:]: row[c] for c in runs.columns if c.startswith("param.") and str(row[c]) != "nan"}
        tip = html.escape(", ".join(f"{k}={v}" for k, v in all_params.items()))
        cells = [f'<td class="text" title="{tip}">{html.escape(str(row["label"]))}</td>']
        cells += [f"<td>{_cell(row[c])}</td>" for c in params]
        cells += [f"<td>{_cell(row['frame_ms'])}</td>", f"<td>{_cell(row['error'])}</td>",
                  f"<td>{_cell(row.get('baseline_error', math.nan))}</td>",
                  f'<td class="text">{html.escape(str(row["status"]))}</td>']
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return (f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
            "<p>Click a column to sort; hover a method for all its parameters.</p>")


def write_html(sweep_dir, frame, scenes, context, chosen, fig_dir):
    """Writes sweep_dir/report.html (a temporary name renamed into place); returns its path."""
    parts = ["<!DOCTYPE html><html><head><meta charset=\"utf-8\">",
             f"<title>Sweep report: {html.escape(os.path.basename(os.path.abspath(sweep_dir)))}</title>",
             f"<style>{STYLE}</style><script>{SCRIPT}</script></head><body>",
             f"<h1>Sweep report: {html.escape(os.path.basename(os.path.abspath(sweep_dir)))}</h1>",
             f"<p>{bold(context)}</p>"]
    for scene in scenes:
        parts.append(f"<h2>{html.escape(scene)}</h2>")
        figure = os.path.join(fig_dir, f"time_vs_error_{scene}.png")
        if os.path.exists(figure):
            parts.append(f'<figure><img alt="time vs error, {html.escape(scene)}" src="{file_uri(figure)}">'
                         "<figcaption>Error against frame time (report.md gives the caption in full).</figcaption>"
                         "</figure>")
        parts.append(runs_table(frame, scene))
        block = image_comparison(frame, scene, sweep_dir, chosen)
        if block:
            parts.append("<h3>Receiver maps: truth against each method</h3>" + block)
    parts.append("</body></html>")
    path = os.path.join(sweep_dir, "report.html")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(parts) + "\n")
    os.replace(path + ".tmp", path)
    return path
