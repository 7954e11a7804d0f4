#!/usr/bin/env bash
# Installs the real parts fsrlab is checked against: ngspice (circuit validation),
# the AVR toolchain and Debian's Arduino core (firmware build), avrdude (flashing an Uno), simavr (firmware runs
# in a simulated ATmega328P), Chromium and its WebDriver (browser tests of `fsrlab live`).
# Installs only what is missing; needs root (or sudo).
set -u
packages=(ngspice gcc-avr avr-libc arduino-core-avr avrdude simavr libsimavr-dev chromium chromium-driver)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
if ! command -v apt-get >/dev/null 2>&1; then
  echo "sysdeps: apt-get not found; install by hand: ${missing[*]}" >&2
  exit 0
fi
if [ "$(id -u)" -eq 0 ]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  sudo=(sudo -n)
else
  echo "sysdeps: not root; tests needing ${missing[*]} will skip (install them with apt-get)" >&2
  exit 0
fi
echo "sysdeps: installing ${missing[*]}"
"${sudo[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
