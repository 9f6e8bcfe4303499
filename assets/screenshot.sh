#!/usr/bin/env bash
# Regenerates assets/screenshot.png, the picture in README.md: the viewer under Xvfb (software
# Vulkan where there is no GPU) at its default window and camera, the 15 mm probe pressed 4 mm
# into the centre of the top face, 300 frames, then the window as shown saved by `view --screenshot`.
# Needs the packages .ci/run installs (xvfb, xauth, mesa-vulkan-drivers, ...).
set -euo pipefail
cd "$(dirname "$0")/.."
lvp=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
if [ -z "${VK_ICD_FILENAMES:-}" ] && [ -f "$lvp" ] && ! command -v nvidia-smi >/dev/null; then
  export VK_ICD_FILENAMES="$lvp"
fi
cargo build --release --locked
xvfb-run -a -s "-screen 0 1280x800x24" target/release/tissue-sim view --press 0.05,0.05,0.004 --frames 300 \
  --screenshot assets/screenshot.png
echo "wrote assets/screenshot.png"
