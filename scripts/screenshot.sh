#!/usr/bin/env bash
# A screenshot of a run's index.html as a browser shows it:
#   scripts/screenshot.sh out/pipeline [WIDTH HEIGHT]  ->  out/pipeline/index_screenshot.png
# Uses headless Chromium (Debian: `apt-get install chromium`; or name one in HAUNTS_CHROMIUM).
# tests/report_render.rs checks the same way that a report's figures show.
set -euo pipefail
dir=${1:?usage: screenshot.sh DIR [WIDTH HEIGHT]}
width=${2:-1200}
height=${3:-12000}
browser=${HAUNTS_CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}
if [ -z "$browser" ]; then
    echo "screenshot.sh: no chromium (apt-get install chromium, or set HAUNTS_CHROMIUM)" >&2
    exit 2
fi
page=$(cd "$dir" && pwd)/index.html
[ -f "$page" ] || { echo "screenshot.sh: no $page" >&2; exit 2; }
"$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars \
    --window-size="$width,$height" --screenshot="$(dirname "$page")/index_screenshot.png" \
    "file://$page" 2>/dev/null
echo "$(dirname "$page")/index_screenshot.png"
