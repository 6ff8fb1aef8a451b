#!/usr/bin/env bash
# Installs every build/test dependency from Debian 12's packages. Idempotent:
# apt-get skips what is already installed. Needs root (or sudo).
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
packages=(
  build-essential cmake pkg-config
  libepoxy-dev libglm-dev pybind11-dev libopenexr-dev libpng-dev libgtest-dev
  python3.11-dev python3-numpy python3-openimageio python3-matplotlib
  libegl-mesa0 libegl-dev libgl1-mesa-dri
  blender xvfb xauth
  slurmctld slurmd slurm-client munge
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "Installing: ${missing[*]}"
  $SUDO apt-get update
  # With recommends: Blender needs some of them at run time (fonts, Mesa bits).
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y "${missing[@]}"
else
  echo "All dependencies are installed."
fi
