#!/usr/bin/env bash
# Installs exactly the Debian packages the project needs. Idempotent: installs nothing when all are
# present. Works as root or through sudo.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git clang libclang-rt-14-dev
  libembree-dev libopenimageio-dev libopenexr-dev libtinygltf-dev libglm-dev libtbb-dev libfftw3-dev
  nlohmann-json3-dev libcli11-dev libgtest-dev libbenchmark-dev libglfw3-dev libimgui-dev xvfb
  python3 python3-matplotlib python3-pandas python3-numpy python3-openimageio chromium
  slurm-wlm munge
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -eq 0 ]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  SUDO=(sudo -n)
else
  echo "setup.sh: missing packages: ${missing[*]}" >&2
  echo "setup.sh: installing them needs root; run as root or with passwordless sudo" >&2
  exit 1
fi

echo "setup.sh: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${SUDO[@]}" apt-get update -q
"${SUDO[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
