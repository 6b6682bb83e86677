#!/usr/bin/env bash
# The CRKSPH paper's 2D shock tests (Noh and Sedov on the quadrant, 100² particles) run with
# every scheme of that paper; prints one markdown table row per run from its summary.json.
# Usage: tools/verify_schemes.sh [--threads N]   (about 15 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=target/release/sphfmu
OUT=target/verify
THREADS=()
if [[ "${1:-}" == "--threads" ]]; then THREADS=(--threads "$2"); fi
mkdir -p "$OUT"
echo "| case | scheme | shock r (exact) | post-shock ρ (exact) | L1(ρ) | energy change | steps | wall s |"
echo "|---|---|---|---|---|---|---|---|"
for model in noh2d-crksph sedov2d-crksph; do
  for scheme in crksph compsph compsph-cullen psph; do
    dir="$OUT/$model-$scheme"
    "$BIN" run "models/$model.toml" --scheme "$scheme" --out "$dir" --quiet "${THREADS[@]}" > "$dir.log" 2>&1 || {
      echo "| $model | $scheme | failed: $(tail -1 "$dir.log") |"; continue; }
    python3 - "$dir/summary.json" "$model" "$scheme" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
r = s["radial"]
e0, e1 = s["initial"]["total_energy"], s["last"]["total_energy"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {r['shock_radius']:.4f} ({r['shock_radius_exact']:.4f}) "
      f"| {r['post_shock_density']:.3f} ({r['post_shock_density_exact']:.3f}) | {r['l1_density']:.4e} "
      f"| {(e1 - e0) / e0:.1e} | {s['steps']} | {s['wall_seconds']:.1f} |")
PY
  done
done
