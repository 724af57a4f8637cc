"""What a reader needs before trusting a scene's ranking: the truth its errors are measured against, how
noisy that truth is next to the smallest error the report ranks, and how many runs carry a caveat."""
import numpy as np

from load import ok_runs

# docs/design.md section 6: reference noise should be a small fraction of every error a report ranks.
DEFAULT_NOISE_RATIO_TARGET = 1.0 / 3.0


def noise_ratio_target(manifest):
    settings = (manifest.get("spec") or {}).get("report") or {}
    return float(settings.get("noise_ratio_target", DEFAULT_NOISE_RATIO_TARGET))


def describe_truth(kinds):
    """'analytic:sine' -> analytic closed form (sine); 'reference' -> Monte Carlo reference."""
    if not kinds:
        return "not recorded by this sweep (older sweeps used the Monte Carlo reference)"
    names = []
    for kind in sorted(kinds):
        if kind.startswith("analytic"):
            names.append(f"analytic closed form ({kind.partition(':')[2] or 'exact'})")
        elif kind == "reference":
            names.append("Monte Carlo reference")
        else:
            names.append(kind)
    return " and ".join(names)


def scene_quality(frame, scene, target):
    """The numbers report.md states for one scene (see `scene_lines`)."""
    runs = ok_runs(frame[frame["scene"] == scene])
    kinds = set(runs["truth"].dropna().astype(str)) if "truth" in runs else set()
    analytic = bool(kinds) and all(k.startswith("analytic") for k in kinds)
    noise = runs["noise_nrmse"].dropna()
    net = runs[runs["error_is_net"] & (runs["error"] > 0)]
    smallest = net.loc[net["error"].idxmin()] if not net.empty else None
    ratio = None
    if analytic:
        ratio = 0.0  # a closed form has no noise to compare with
    elif smallest is not None and np.isfinite(smallest["noise_nrmse"]):
        ratio = float(smallest["noise_nrmse"]) / float(smallest["error"])  # noise of the same frame's truth
    targeted = runs[np.isfinite(runs["noise_target"])] if "noise_target" in runs else runs.iloc[0:0]
    return {"scene": scene, "truth": describe_truth(kinds), "analytic": analytic, "runs": len(runs),
            "noise": 0.0 if analytic else (float(noise.median()) if not noise.empty else None),
            "noise_range": (float(noise.min()), float(noise.max())) if not noise.empty else None,
            "smallest": None if smallest is None else float(smallest["error"]),
            "smallest_label": None if smallest is None else smallest["label"],
            "ratio": ratio, "target": target, "flagged": ratio is not None and ratio > target,
            "below_reference_noise": int(runs["below_reference_noise"].sum()),
            "noisy_timing": int(runs["noisy_timing"].sum()),
            "no_better_than_flat": int(runs["no_better_than_flat"].sum()),
            "noise_target_missed": int((~targeted["noise_target_met"]).sum()),
            "outside_claim": _count_false(runs, "claim_inside"),
            "claim_missed": _count_false(runs, "claim_met")}


def _count_false(runs, column):
    """Runs whose column reads false; an empty cell (not judged, or an older sweep) is not counted."""
    if column not in runs:
        return 0
    return int((runs[column].astype(str).str.strip().str.lower() == "false").sum())


def scene_lines(q):
    """Markdown lines: truth and noise, the noise ratio (flagged above the target), the caveat counts."""
    noise = "--" if q["noise"] is None else f"{q['noise']:.3g}"
    if q["noise_range"] and q["noise_range"][0] != q["noise_range"][1] and not q["analytic"]:
        noise += f" (median; {q['noise_range'][0]:.3g} to {q['noise_range'][1]:.3g} over frames)"
    lines = [f"Truth: {q['truth']}; reference noise nrmse {noise}."]
    if q["smallest"] is None:
        ratio = "No ok run has a positive net error, so there is no noise ratio to check."
    else:
        ratio = (f"Smallest net error reported: {q['smallest']:.3g} ({q['smallest_label']}); "
                 f"noise / smallest net error = {'--' if q['ratio'] is None else format(q['ratio'], '.3g')} "
                 f"(target <= {q['target']:.3g})")
        if q["analytic"]:
            ratio += ", 0 because the truth is analytic."
        elif q["flagged"]:
            ratio += (": **FLAGGED, above the target**: the reference noise is not small next to the best "
                      "errors, so their ranking is not reliable; a reference with more photons (or analytic "
                      "truth) is needed.")
        else:
            ratio += "."
    lines.append(ratio)
    counts = (f"Of {q['runs']} ok runs: {q['below_reference_noise']} below the reference noise (95 % interval "
              f"includes 0), {q['noisy_timing']} with noisy timing, {q['no_better_than_flat']} no better than the "
              f"no-caustic baseline.")
    if q["outside_claim"]:
        counts += (f" {q['outside_claim']} run(s) lie outside their method's claimed regime (results.csv "
                   f"claim_reason says which bound).")
    if q["claim_missed"]:
        counts += (f" **{q['claim_missed']} run(s) missed the accuracy their method claims** "
                   f"(claim_met false: error above the claimed bound).")
    if q["noise_target_missed"]:
        counts += f" {q['noise_target_missed']} run(s) used a reference that missed its noise target."
    lines.append(counts)
    return lines


def _truthy(series):
    return series.astype(str).str.strip().str.lower() == "true"


def claim_rows(frame, scene):
    """Per method on one scene: the runs inside its claimed regime, the bound they were held to (claim_bound:
    the stated absolute nrmse or half the baseline's, the smaller; the largest over the runs) and the worst
    error measured inside it (nrmse, or nrmse after the fit for relative outputs), with whether every run
    held. Only runs judged against an exact truth carry a bound; the others show "--"."""
    runs = ok_runs(frame[frame["scene"] == scene])
    rows = []
    if "claim_inside" not in runs:
        return rows
    for method, group in runs.groupby("method", sort=True):
        inside = group[_truthy(group["claim_inside"])]
        row = {"method": method, "runs": len(group), "inside": len(inside), "stated": None, "bound": None,
               "worst": None, "held": None}
        if "claim_max_error" in inside and inside["claim_max_error"].notna().any():
            row["stated"] = float(inside["claim_max_error"].max())
        judged = inside[inside["claim_bound"].notna()] if "claim_bound" in inside else inside.iloc[0:0]
        if not judged.empty:
            fitted = ~_truthy(judged["radiometric"]) if "radiometric" in judged else False
            error = judged["nrmse_fit"].where(fitted, judged["nrmse"]) if "nrmse_fit" in judged else judged["nrmse"]
            row["bound"] = float(judged["claim_bound"].max())
            row["worst"] = float(error.max())
            row["held"] = bool((error <= judged["claim_bound"]).all())
        rows.append(row)
    return rows


def claim_lines(rows):
    """A markdown table of claim_rows (empty where no method states a claim)."""
    if not rows:
        return []
    f = lambda v: "--" if v is None else f"{v:.3g}"  # noqa: E731
    lines = ["| method | runs | inside its claim | claimed nrmse | bound held to (largest) | worst error inside | held |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        held = "--" if r["held"] is None else ("yes" if r["held"] else "**no**")
        lines.append(f"| {r['method']} | {r['runs']} | {r['inside']} | {f(r['stated'])} | {f(r['bound'])} | "
                     f"{f(r['worst'])} | {held} |")
    return lines
