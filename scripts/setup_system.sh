#!/usr/bin/env bash
# System packages isu-validate needs, installed through Debian's apt when missing.
# - libraries bpy links against (X11 client libs, GL)
# - WordNet 3.0 for METEOR (copied into nltk_data by `python -m isu_validate.setup_data`)
# - chromium for the report's browser test and the recreation sheets' print test
set -euo pipefail
PKGS=(libx11-6 libxrender1 libxfixes3 libxi6 libxkbcommon0 libxext6 libxcb1 libsm6 libice6 libxt6 libgl1
      wordnet-base wordnet-sense-index chromium)
missing=()
for p in "${PKGS[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing system packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
