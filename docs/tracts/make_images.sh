#!/usr/bin/env bash
# Images of docs/tracts.md, made by brainpainter itself from dipy's minimal bundles (BSD-3, read from
# dipy's installed wheel: dipy/data/files/minimal_bundles.zip, subject 1: AF_L, CST_R, CC_ForcepsMajor;
# nothing is downloaded). Needs: pip install dipy.  Run: bash docs/tracts/make_images.sh
set -euo pipefail
cd "$(dirname "$0")"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python - "$work" <<'PY'
import sys, zipfile
from pathlib import Path
import dipy, numpy as np
work = Path(sys.argv[1])
zipfile.ZipFile(Path(dipy.__file__).parent / "data" / "files" / "minimal_bundles.zip").extractall(work)
# The bundles are in RAS millimetres of some subject, not MNI152: the forceps major lies ~25 mm too low.
# This translation (chosen by eye, not a registration) puts them inside the fsaverage brain.
np.savetxt(work / "place.txt", [[1, 0, 0, 0], [0, 1, 0, -10], [0, 0, 1, 25], [0, 0, 0, 1]])
# made-up values, for the pictures only
(work / "fa.csv").write_text("Image-name-unique,AF_L,CST_R,CC_ForcepsMajor\npatients,0.41,0.55,0.68\n")
(work / "thickness.csv").write_text(
    "Image-name-unique,Left-Hippocampus,Right-Hippocampus,Left-Thalamus,Right-Thalamus,"
    "Left-Putamen,Right-Putamen\npatients,0.35,0.45,0.62,0.58,0.50,0.48\n")
rows = [(b, k, v) for b, f in (("AF_L", 1.0), ("CST_R", 2.0), ("CC_ForcepsMajor", 3.0))
        for k, v in zip(range(100), 0.3 + 0.3 * (np.sin(np.linspace(0, f * np.pi, 100)) + 1) / 2)]
# one table with region columns (the example's stage 3) and bundle columns, for the cortex views
import csv
dk_rows = list(csv.reader(open("../../examples/brainpainter_dk.csv")))
(work / "cortex.csv").write_text(",".join([*dk_rows[0], "AF_L", "CST_R", "CC_ForcepsMajor"]) + "\n"
                                 + ",".join(["patients", *dk_rows[3][1:], "1.2", "2.0", "2.8"]) + "\n")
(work / "profiles.csv").write_text("bundle,node,fa\n" + "".join(f"{b},{k},{v:.3f}\n" for b, k, v in rows))
PY
common=(--tracts "$work/sub_1" --tracts-space fsaverage --tracts-affine "$work/place.txt" --tract-radius 0.4
        --hide ventricles --hide brainstem --hide cerebellum)
# 1. no values: direction colours (red left-right, green anterior-posterior, blue inferior-superior)
brainpainter render "$work/thickness.csv" "${common[@]}" --missing-color "#cccccc" --views subcortical,subcortical-dorsal \
    --size 600x450 --out "$work/direction"
python - "$work" <<'PY'
import sys
from pathlib import Path
from PIL import Image
w = Path(sys.argv[1]) / "direction"
ims = [Image.open(w / f"patients_{v}.png").convert("RGB") for v in ("subcortical", "subcortical-dorsal")]
sheet = Image.new("RGB", (sum(i.width for i in ims), ims[0].height), "white")
for k, im in enumerate(ims):
    sheet.paste(im, (k * ims[0].width, 0))
sheet.save("direction.png", optimize=True)
PY
# 2. one figure, one colour scale: FA per bundle and values per subcortical structure
brainpainter figure "$work/thickness.csv" "${common[@]}" --tract-values "$work/fa.csv" --vmin 0.3 --vmax 0.7 \
    --cmap viridis --views subcortical,subcortical-dorsal --label "FA / structure value" --out bundles.png
# 3. along-tract profiles: 100 nodes per bundle
brainpainter figure "$work/thickness.csv" "${common[@]}" --tract-values "$work/profiles.csv" --vmin 0.3 --vmax 0.6 \
    --cmap plasma --views subcortical,subcortical-left --label "FA along the bundle" --out profiles.png
# 4. the cortex views: the bundles of the view's hemispheres through the cortex drawn as glass (--cortex glass;
#    auto draws a cortex that carries values opaque, in the colours of its colour bar)
brainpainter render "$work/cortex.csv" --atlas dk "${common[@]}" --cortex glass \
    --views lateral-left,medial-left,dorsal,subcortical \
    --size 600x450 --out "$work/cortex"
python - "$work" <<'PY'
import sys
from pathlib import Path
from PIL import Image
w = Path(sys.argv[1]) / "cortex"
ims = [Image.open(w / f"patients_{v}.png").convert("RGB")
       for v in ("lateral-left", "medial-left", "dorsal", "subcortical")]
sheet = Image.new("RGB", (2 * ims[0].width, 2 * ims[0].height), "white")
for k, im in enumerate(ims):
    sheet.paste(im, ((k % 2) * ims[0].width, (k // 2) * ims[0].height))
sheet.save("cortex.png", optimize=True)
PY
# a smaller file: a 256-colour palette (not for the figures: their colour bars would show bands)
python - <<'PY'
from PIL import Image
for p in ("direction.png", "cortex.png"):
    Image.open(p).convert("RGB").quantize(256, method=Image.Quantize.MEDIANCUT).save(p, optimize=True)
PY
