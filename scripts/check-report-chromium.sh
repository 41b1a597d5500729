#!/usr/bin/env bash
# Opens the HTML report of `gsens report` in headless Chromium and checks that
# it rendered: the page loads without console errors or failed requests, every
# figure is an inline SVG in the DOM, the estimate and the verdicts are there,
# and a screenshot shows a non-trivial page; and that the report of an
# untrustworthy estimate shows its verdict.
#
# Not part of `cargo test` (CI has no browser). Needs Debian's `chromium`
# package: installed here when missing and running as root.
#
# Usage: scripts/check-report-chromium.sh [OUT_DIR]
#   OUT_DIR (default: a temporary folder) receives the simulated logs, the
#   report, the DOM dump, Chromium's log and the screenshot `screenshot.png`;
#   then the same for the session's IMU log rewritten in g, an untrustworthy
#   estimate (`untrusted/`, `screenshot-untrusted.png`).
#   GSENS=path/to/gsens uses that binary instead of building one.
set -euo pipefail
cd "$(dirname "$0")/.."

fail() { echo "FAIL: $*" >&2; exit 1; }

if ! command -v chromium >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ]; then
        echo "installing chromium …"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
    else
        fail "chromium is not installed (apt-get install chromium)"
    fi
fi

out=${1:-$(mktemp -d)}
mkdir -p "$out"
if [ -z "${GSENS:-}" ]; then
    cargo build -q -p gsens-cli
    GSENS=target/debug/gsens
fi
cargo build -q -p gsens-report --example png_stats
png_stats=target/debug/examples/png_stats

# A simulated session (the paper's experiment) and its report.
"$GSENS" simulate --out "$out/sim" >/dev/null
# The receiver loop the simulator ran, as `gsens demo` passes it.
loop_t=$(sed -n 's/^ *"loop_interval_s": *\([0-9.eE+-]*\),*$/\1/p' "$out/sim/truth.json" | head -n1)
logged=$(sed -n 's/^ *"logged_phase": *"\([a-z]*\)",*$/\1/p' "$out/sim/truth.json" | head -n1)
"$GSENS" report --imu "$out/sim/imu.csv" --tracking "$out/sim/tracking.csv" --truth "$out/sim/truth.json" \
    ${loop_t:+--loop-interval-s "$loop_t"} ${logged:+--logged-phase "$logged"} --out "$out/report" >/dev/null
html="$(cd "$out/report" && pwd)/report.html"
[ -s "$html" ] || fail "no report.html"

chrome=(chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run
    --disable-background-networking --disable-component-update --disable-sync
    --user-data-dir="$out/chromium-profile")
shot="$out/screenshot.png"
rm -f "$shot"
timeout 120 "${chrome[@]}" --enable-logging=stderr --v=0 --window-size=1280,2000 \
    --screenshot="$shot" "file://$html" >"$out/chromium.log" 2>&1 || fail "chromium failed (see $out/chromium.log)"
timeout 120 "${chrome[@]}" --dump-dom "file://$html" >"$out/dom.html" 2>>"$out/chromium.log" \
    || fail "chromium --dump-dom failed"

# Console errors (uncaught exceptions, console.error) and failed loads.
if grep -E "CONSOLE|Uncaught|net::ERR_|Failed to load|Refused to" "$out/chromium.log"; then
    fail "console errors or failed requests (above; full log: $out/chromium.log)"
fi

# Self-contained: nothing to fetch (no image, script, style sheet or frame).
if grep -Eo '<(img|script|link|iframe|object|embed)[ >]' "$out/dom.html"; then
    fail "the page references external content"
fi

# The figures are in the DOM as SVG, one per <figure>, as many as report.json lists.
n_json=$(grep -c '"title": ' "$out/report/report.json" || true)
n_fig=$(grep -o '<figure id=' "$out/dom.html" | wc -l)
n_svg=$(grep -o '<svg ' "$out/dom.html" | wc -l)
n_text=$(grep -o '<text ' "$out/dom.html" | wc -l)
[ "$n_fig" -ge 4 ] || fail "only $n_fig figures in the DOM"
[ "$n_svg" -eq "$n_fig" ] || fail "$n_svg SVGs for $n_fig figures"
[ "$n_text" -ge 40 ] || fail "only $n_text SVG text elements (labels missing?)"
[ "$n_json" -ge "$n_fig" ] || fail "report.json lists fewer figures than the page shows"
for needle in 'id="verdict"' 'id="estimate-table"' 'id="rms-before"' 'id="rms-after"' 'id="settings-table"' \
    'GSENS_GAMMA_X_HZ_PER_MPS2' 'observable'; do
    grep -q "$needle" "$out/dom.html" || fail "the rendered page lacks $needle"
done
for f in fig3_response fig4_estimation fig5_compensation; do
    grep -q "<figure id=\"$f\"" "$out/dom.html" || fail "the page lacks $f"
    [ -s "$out/report/figures/$f.png" ] && [ -s "$out/report/figures/$f.svg" ] || fail "no $f.png/.svg"
done

# The screenshot: the window's size, many colours, a good part of it drawn.
[ -s "$shot" ] || fail "no screenshot"
read -r w h colours ink < <("$png_stats" "$shot")
[ "$w" = 1280 ] && [ "$h" = 2000 ] || fail "screenshot is ${w}x${h}, expected 1280x2000"
[ "$colours" -ge 500 ] || fail "screenshot has only $colours colours"
awk -v ink="$ink" 'BEGIN { exit !(ink > 0.05) }' || fail "screenshot is nearly blank (ink $ink)"

echo "OK: report rendered in Chromium: $n_fig figures as inline SVG ($n_text text elements), no console errors;"
echo "    screenshot ${w}x${h}, $colours colours, $(awk -v i="$ink" 'BEGIN{printf "%.0f", i*100}') % drawn: $shot"

# The same session with its IMU log in g (imu_units): the report must say NOT
# TRUSTWORTHY in a red banner above the table, strike through the Γ̂ cells,
# show no green "complete" note, and come without gsens_gamma.h.
awk -F, -v OFS=, -v CONVFMT=%.17g -v OFMT=%.17g 'NR == 1 { print; next } { $2 /= 9.80665; $3 /= 9.80665; $4 /= 9.80665; print }' \
    "$out/sim/imu.csv" >"$out/sim/imu_g.csv"
status=0
"$GSENS" report --imu "$out/sim/imu_g.csv" --tracking "$out/sim/tracking.csv" --truth "$out/sim/truth.json" \
    ${loop_t:+--loop-interval-s "$loop_t"} ${logged:+--logged-phase "$logged"} --out "$out/untrusted" \
    >/dev/null 2>"$out/untrusted.stderr" || status=$?
[ "$status" = 3 ] || fail "gsens report on an IMU log in g exited with $status, not 3"
[ ! -e "$out/untrusted/gsens_gamma.h" ] || fail "a gsens_gamma.h for an untrustworthy estimate"
html_u="$(cd "$out/untrusted" && pwd)/report.html"
shot_u="$out/screenshot-untrusted.png"
rm -f "$shot_u"
timeout 120 "${chrome[@]}" --window-size=1280,1000 --screenshot="$shot_u" "file://$html_u" >>"$out/chromium.log" 2>&1 \
    || fail "chromium failed on the untrustworthy report"
timeout 120 "${chrome[@]}" --dump-dom "file://$html_u" >"$out/dom-untrusted.html" 2>>"$out/chromium.log" \
    || fail "chromium --dump-dom failed on the untrustworthy report"
grep -q 'id="verdict" role="alert">NOT TRUSTWORTHY (imu_units)' "$out/dom-untrusted.html" || fail "no red verdict banner"
grep -q '<li><code>imu_units</code>' "$out/dom-untrusted.html" || fail "the banner does not list imu_units"
! grep -q 'Γ̂ is complete' "$out/dom-untrusted.html" || fail "the green note on an untrustworthy estimate"
n_marked=$(grep -o 'class="num untrusted"' "$out/dom-untrusted.html" | wc -l)
[ "$n_marked" -eq 6 ] || fail "$n_marked Γ̂ cells marked, expected 6"
[ -s "$shot_u" ] || fail "no screenshot of the untrustworthy report"
echo "OK: the untrustworthy report (IMU in g): red banner with imu_units, 6 Γ̂ cells struck through, no header: $shot_u"
