#!/usr/bin/env bash
# Installs qemu-system-arm (QEMU 7.2 to 10.x all work) on Debian or Ubuntu, as root:
#   bash xtask/install-qemu.sh
# On Debian 12 machines whose QEMU tools already come from bookworm-backports (qemu-utils
# 10.x), the release's QEMU 7.2 cannot be installed beside them (qemu-utils 10 Breaks
# qemu-system-common < 8.0): qemu-system-arm is then taken from the same backports suite, which
# is added to apt's sources if it is missing. Elsewhere it comes from the release.
set -euo pipefail

if command -v qemu-system-arm >/dev/null; then
    qemu-system-arm --version | head -1
    exit 0
fi
if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null; then
    echo "qemu-system-arm is missing: install it with your package manager (Debian/Ubuntu, as root: bash xtask/install-qemu.sh; Fedora: dnf install qemu-system-arm; macOS: brew install qemu)" >&2
    exit 1
fi
run() { printf '+ %s\n' "$*"; "$@"; }
trap 'echo "installing qemu-system-arm failed (see above); install QEMU 7.2 to 10.x by hand and put qemu-system-arm on PATH, or name it with BEAMFIELD_QEMU" >&2' ERR
export DEBIAN_FRONTEND=noninteractive

# Installed QEMU packages from a backports suite, e.g. "qemu-utils 1:10.0.2+ds-2+deb13u1~bpo12+1".
backports=$(dpkg-query -W -f='${db:Status-Abbrev} ${Package} ${Version}\n' 'qemu-*' 2>/dev/null \
    | awk '$1 == "ii" && $3 ~ /~bpo/ {print $2 " " $3}' || true)
if [ -z "$backports" ]; then
    run apt-get update
    run apt-get install -y --no-install-recommends qemu-system-arm
else
    . /etc/os-release
    suite="${VERSION_CODENAME:?no VERSION_CODENAME in /etc/os-release}-backports"
    echo "QEMU packages from backports are installed ($(echo "$backports" | tr '\n' ' ')): qemu-system-arm comes from $suite"
    if ! grep -rqs -- "$suite" /etc/apt/sources.list /etc/apt/sources.list.d/; then
        # The same mirror as the release's own suites.
        mirror=$(grep -rhE '^[[:space:]]*(URIs:|deb[[:space:]])' /etc/apt/sources.list /etc/apt/sources.list.d/ 2>/dev/null \
            | grep -oE 'https?://[^ ]+' | grep -E '/debian/?$' | head -1 || true)
        mirror=${mirror:-http://deb.debian.org/debian}
        echo "adding $suite ($mirror) to /etc/apt/sources.list.d/beamfield-backports.list"
        echo "deb $mirror $suite main" > /etc/apt/sources.list.d/beamfield-backports.list
    fi
    run apt-get update
    run apt-get install -y --no-install-recommends -t "$suite" qemu-system-arm
fi
qemu-system-arm --version | head -1
