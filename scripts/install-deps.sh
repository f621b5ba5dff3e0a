#!/usr/bin/env bash
# Installs every Debian 12 package p2i needs. Idempotent and non-interactive:
# runs `apt-get update` once and only when something is missing.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git
  libtorch-dev
  # gloo headers: torch's c10d ProcessGroupGloo (data-parallel training, model/distributed.*)
  libgloo-dev
  libopencv-dev libopencv-contrib-dev
  libeigen3-dev
  libzmq3-dev cppzmq-dev
  libyaml-cpp-dev
  catch2
  libprotobuf-dev protobuf-compiler
  libspdlog-dev libcli11-dev nlohmann-json3-dev
  libaravis-dev libusb-1.0-0-dev aravis-tools
  gnuplot-nox
  # optimised BLAS for LibTorch (Debian's libtorch links the generic libblas.so.3; without this
  # it is the netlib reference BLAS, ~15x slower; the OpenMP build shares LibTorch's libgomp)
  libopenblas0-openmp
  libopen3d-dev libboost-dev
  libwebsocketpp-dev libzstd-dev liblz4-dev zlib1g-dev
  python3-zmq python3-protobuf
  iproute2
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
