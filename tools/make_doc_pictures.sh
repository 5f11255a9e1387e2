#!/bin/sh
# Renders the documentation's pictures into docs/images/ with the built program:
#   before-after.png  the built-in test scene as rendered (sRGB display) and as printed
#                     (Kodak Vision3 250D on Kodak 2383)
#   vision3-250d.png  a stock's curves, sensitivities, dyes and MTF (darkroom plot)
#   grain-compare.png a profile (Vision3 500T scanned at 2K, predicted) against the grain
#                     measured back from a grey ramp it was synthesised onto
# Usage: tools/make_doc_pictures.sh [BUILD_DIR [IMAGES_DIR]]   (default build, docs/images)
set -eu
cd "$(dirname "$0")/.."
darkroom=$(realpath "${1:-build}")/cli/darkroom
images=${2:-docs/images}
mkdir -p "$images"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

"$darkroom" demo -o "$scratch/demo" > /dev/null
"$darkroom" colorconfig -o "$scratch/darkroom.ocio" > /dev/null
# The scene as a renderer shows it (linear to the sRGB display), then the print's PNG, side by side.
oiiotool --colorconfig "$scratch/darkroom.ocio" "$scratch/demo/scene.exr" --ociodisplay sRGB Standard \
         -ch R,G,B "$scratch/demo/print.png" -ch R,G,B --mosaic 2x1 --resize 1024x0 -d uint8 -o "$images/before-after.png"
"$darkroom" plot kodak-vision3-250d -o "$images/vision3-250d.png" > /dev/null
"$darkroom" grain predict --stock kodak-vision3-500t --width 2048 -o "$scratch/plate-grain.json" > /dev/null
oiiotool --pattern fill:left=0.15,0.15,0.15:right=0.95,0.95,0.95 1024x512 3 -d float -o "$scratch/ramp.exr"
# (The ramp's values are Cineon log code values / 1023, the profile's encoding.)
"$darkroom" grain apply "$scratch/ramp.exr" -o "$scratch/grained.exr" --profile "$scratch/plate-grain.json" \
    --iscolorspace "Cineon Log" > /dev/null
"$darkroom" grain analyze "$scratch/grained.exr" -o "$scratch/measured.json" --iscolorspace "Cineon Log" > /dev/null
"$darkroom" grain compare "$scratch/plate-grain.json" "$scratch/measured.json" --plot "$images/grain-compare.png" \
    > /dev/null || true  # (a chart either way; the tests judge the match)
echo "wrote $images/before-after.png, vision3-250d.png, grain-compare.png"
