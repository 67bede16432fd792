#!/usr/bin/env bash
# Installs every Debian package raysort needs to build, test and run on PoCL.
# Idempotent: packages already installed are skipped by apt-get; safe to run twice.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git
  ocl-icd-opencl-dev opencl-c-headers opencl-clhpp-headers pocl-opencl-icd clinfo
  # fonts-dejavu-core: the font the result-set plots are labelled with
  libtinyobjloader-dev libopenimageio-dev fonts-dejavu-core
  googletest libgtest-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev libfmt-dev
  # libgmp-dev: exact rationals for the oracle of `raysort trace --adjudicate`
  libgmp-dev
  # python3: scripts/claims.py, the ctest `claims` (every quoted figure recomputed) and the result scripts
  python3
  # libssl-dev: libcrypto's SHA-256, to check real scene files against scenes/sources.toml
  libssl-dev
  # libtinygltf-dev: glTF 2.0 scenes (.gltf, .glb; host/scene/gltf_loader.cpp)
  libtinygltf-dev
  # oclgrind: a second OpenCL implementation with race and memory checks (scripts/oclgrind-check.sh);
  # clang-15, libclc-15: the NVIDIA (nvptx64-nvidia-nvcl) build of every kernel (scripts/nvptx-build.sh)
  oclgrind clang-15 libclc-15
  #: optional: Boost.Compute (header-only) is the sortbench's reference GPU-library sort
  libboost-dev
  #: optional: Embree 3, the CPU anchor of `raysort trace --reference embree` (CMake RAYSORT_EMBREE=AUTO
  #: uses it when found; the build and tests work without it)
  libembree-dev
)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  SUDO="sudo"
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ "${#missing[@]}" -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "install-deps: done"
