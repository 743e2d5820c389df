#!/usr/bin/env bash
# setup-debian.sh: install everything this project needs on Debian 12.
#
#   ./cmake/setup-debian.sh
#
# Idempotent and fast when everything is present: dpkg-query first, then
# apt-get update + install only the missing packages (--no-install-recommends,
# noninteractive; sudo only when not already root). Finally, if the SocketCAN
# VM tests' fetch script exists, runs it (it caches the Debian kernel package
# those tests boot).
set -euo pipefail

# ---------------------------------------------------------------------------
# PACKAGES -- extend this list (one package per line, with what needs it).
# ---------------------------------------------------------------------------
PACKAGES=(
  # build
  cmake g++ make pkg-config
  # cross toolchain for the Cortex-M7 images (presets stm32h743, qemu-m7)
  gcc-arm-none-eabi binutils-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
  # emulators: QEMU mps2-an500 on-target tests; x86 VM for SocketCAN tests
  qemu-system-arm qemu-system-x86
  # host libraries: Eigen (HIL plant), libmodbus (Modbus tools), CppUTest, benchmarks
  libeigen3-dev libmodbus-dev cpputest libbenchmark-dev
  # CAN tooling, flashing/debug
  can-utils openocd
  # scripts and plots
  python3 python3-matplotlib python3-numpy
  # the lab Python package (host-tools/python/maglev): Modbus client; its serial
  # transport imports serial_asyncio (a Recommends of python3-pymodbus); pip install
  # --no-build-isolation host-tools/python needs setuptools
  python3-pymodbus python3-serial-asyncio python3-setuptools
  # independent readers of maglev-hil's --can-log: candump log + DBC decode (tests/can check_can_log.py)
  python3-can python3-canmatrix
  # SocketCAN VM: initramfs building, serial/socket plumbing, kernel modules
  busybox-static cpio socat kmod xz-utils bc
  # apt-get source (CppUTest sources for the on-target kernel suites)
  dpkg-dev
  # analysis: clang (+ its sanitizer runtimes), valgrind
  clang libclang-rt-14-dev valgrind
)
# ---------------------------------------------------------------------------

if [[ ! -r /etc/debian_version ]]; then
  echo "setup-debian.sh: this script is for Debian 12 (bookworm)." >&2
  exit 1
fi

missing=()
for package in "${PACKAGES[@]}"; do
  status=$(dpkg-query -W -f='${db:Status-Status}' "$package" 2>/dev/null || true)
  if [[ "$status" != "installed" ]]; then
    missing+=("$package")
  fi
done

if ((${#missing[@]} > 0)); then
  echo "setup-debian.sh: installing: ${missing[*]}"
  SUDO=()
  if [[ $(id -u) -ne 0 ]]; then
    SUDO=(sudo)
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
else
  echo "setup-debian.sh: all ${#PACKAGES[@]} packages already installed."
fi

repo_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
fetch_vm_packages="$repo_root/tests/socketcan-vm/fetch-vm-packages.sh"
if [[ -x "$fetch_vm_packages" ]]; then
  echo "setup-debian.sh: running tests/socketcan-vm/fetch-vm-packages.sh"
  "$fetch_vm_packages"
fi

# CppUTest sources for the kernel suites cross-compiled for the M7 (qemu-m7
# preset, tests/target/cpputest_m7): apt-get source cpputest into build/deps.
fetch_cpputest_source="$repo_root/tests/target/cpputest_m7/fetch-cpputest-source.sh"
if [[ -x "$fetch_cpputest_source" ]]; then
  echo "setup-debian.sh: running tests/target/cpputest_m7/fetch-cpputest-source.sh"
  "$fetch_cpputest_source"
fi
