#!/usr/bin/env bash
# report.html in a real browser: a small sweep and its report, then the page opened in headless Chromium
# (Debian's chromium, installed by scripts/setup.sh). Passes when the page names no network resource, loads
# without console errors, every image decodes and the comparison's slider and difference toggle change the
# shown image (the page's own #selftest, run by the browser, writes the verdict into its title); a
# screenshot is left in OUT/report_html.png. compare.html (`caustics compare`) must load the same way.
#
# Usage: browser_test.sh CAUSTICS_BINARY OUT_DIR
set -euo pipefail
bin=$1
out=$2
fail() { echo "report_html: FAILED: $*" >&2; exit 1; }
browser=$(command -v chromium || command -v chromium-browser || true)
[ -n "$browser" ] || fail "no chromium on PATH (scripts/setup.sh installs Debian's chromium)"
rm -rf "$out"
mkdir -p "$out"
cat > "$out/spec.json" <<'SPEC'
{"scenes": ["sine"], "truth": "analytic", "reference": {"photons": 20000},
 "timing": {"warmup": 0, "repeats": 3, "precision": 1, "max_time_s": 0.2},
 "methods": {"caustic_triangles": {"grid": [32, 64]}, "eikonal_fmm": {"grid": [32]}}}
SPEC
"$bin" sweep "$out/spec.json" --out "$out/sweep" --cache "$out/cache" > "$out/sweep.log" 2>&1 || fail "sweep (see $out/sweep.log)"
"$bin" report "$out/sweep" > "$out/report.log" 2>&1 || fail "report (see $out/report.log)"
page="$out/sweep/report.html"
[ -s "$page" ] || fail "no report.html beside report.md"
if grep -Eq '(src|href)="(https?:)?//' "$page"; then fail "the page loads something from the network"; fi
flags=(--headless=new --no-sandbox --disable-gpu --hide-scrollbars --virtual-time-budget=10000)
title=$(timeout 120 "$browser" "${flags[@]}" --enable-logging=stderr --v=0 --dump-dom "file://$page#selftest" \
          2> "$out/console.log" | grep -o '<title>[^<]*</title>' || true)
echo "report_html: $title"
[[ $title == *"selftest: ok"* ]] || fail "the page's self-test says: ${title:-nothing (it did not run)}"
if grep -E 'CONSOLE|Uncaught' "$out/console.log"; then fail "console messages (see $out/console.log)"; fi
timeout 120 "$browser" "${flags[@]}" --window-size=1200,1600 --screenshot="$out/report_html.png" "file://$page" \
  > /dev/null 2>&1 || fail "no screenshot"
[ "$(stat -c %s "$out/report_html.png")" -gt 10000 ] || fail "the screenshot is empty"
# compare.html (`caustics compare`, the sweep against itself) loads with its figure and without console messages.
"$bin" compare "$out/sweep" "$out/sweep" --out "$out/compare" > "$out/compare.log" 2>&1 || fail "compare (see $out/compare.log)"
dom=$(timeout 120 "$browser" "${flags[@]}" --enable-logging=stderr --v=0 --dump-dom "file://$out/compare/compare.html" \
        2> "$out/compare_console.log")
[[ $dom == *"<title>Sweep comparison</title>"* && $dom == *"data:image/png;base64,"* ]] || fail "compare.html did not load"
if grep -E 'CONSOLE|Uncaught' "$out/compare_console.log"; then fail "console messages (see $out/compare_console.log)"; fi
echo "report_html: ok; screenshot $out/report_html.png"
