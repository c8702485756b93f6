#!/bin/sh
# The PIC18 board's compiler: sdcc with its pic16 port, built once from
# Debian's own sdcc source package into a cache that later runs reuse
# (docs/boards.md, "The PIC18 board", "Toolchain").
#
#   boards/pic18/toolchain/build.sh [PREFIX]
#
# PREFIX defaults to $EASYLAB_PIC18_SDCC, else
# ${XDG_CACHE_HOME:-$HOME/.cache}/easylab/sdcc-pic16-<version>. A finished
# build leaves PREFIX/.easylab-complete; with it present nothing is done.
#
# Debian's sdcc is built without the PIC ports, and Microchip's device
# headers and libraries are non-free (absent from the source too). So:
#   1. a deb-src entry for this release, the build dependencies from apt;
#   2. `apt-get source sdcc`, configured with every port but pic16 off; the
#      pic16 library build includes two non-free autoconf fragments that the
#      Debian source lacks: empty ones are enough (old time stamps, so that
#      make does not try to run autoconf); the libraries are compiled for
#      the large stack model, as the board's code is (its software stack is
#      larger than a 256-byte bank, and a small-model library function
#      would address its arguments in the wrong bank);
#   3. make, make install into PREFIX (about 3 minutes on 2 cores);
#   4. device headers and device libraries of the board's parts, generated
#      from gputils' .inc files (device_headers.py), archived with gplib.
# Output is short; everything else goes to PREFIX.log, shown on failure.
# Needs root (or sudo) for apt. No stdin is read.
set -eu

SDCC_VERSION=4.2.0
RECIPE=2  # bump when the recipe changes: a new cache folder is built (and sdcc.py's VERSION_FOLDER)
PARTS="18f4520 18f4620"
HERE=$(cd "$(dirname "$0")" && pwd)
PREFIX=${1:-${EASYLAB_PIC18_SDCC:-${XDG_CACHE_HOME:-$HOME/.cache}/easylab/sdcc-pic16-$SDCC_VERSION-$RECIPE}}
STAMP=$PREFIX/.easylab-complete
LOG=$PREFIX.log

[ -f "$STAMP" ] && exit 0

mkdir -p "$(dirname "$PREFIX")"
: > "$LOG"
echo "Building sdcc $SDCC_VERSION with the pic16 port into $PREFIX (a few minutes, once; log: $LOG)"

fail() {
    tail -n 40 "$LOG" >&2
    echo "build.sh: $1 (full log: $LOG)" >&2
    exit 1
}

SUDO=
if [ "$(id -u)" != 0 ]; then
    command -v sudo > /dev/null || fail "apt needs root: run as root or install sudo"
    SUDO=sudo
fi
APT="$SUDO env DEBIAN_FRONTEND=noninteractive apt-get -q -y -o DPkg::Lock::Timeout=600 -o APT::Sandbox::User=root"

# ---- 1. sources and build dependencies
. /etc/os-release
CODENAME=${VERSION_CODENAME:-bookworm}
if ! grep -rqs "deb-src" /etc/apt/sources.list /etc/apt/sources.list.d/ 2>/dev/null; then
    printf 'Types: deb-src\nURIs: http://deb.debian.org/debian\nSuites: %s\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
        "$CODENAME" | $SUDO tee /etc/apt/sources.list.d/easylab-deb-src.sources > /dev/null
    $APT update >> "$LOG" 2>&1 || fail "apt-get update failed"
fi
$APT install --no-install-recommends bison flex libboost-dev libtool texinfo zlib1g-dev libncurses-dev \
    dpkg-dev g++ make gputils >> "$LOG" 2>&1 || fail "installing sdcc's build dependencies failed"

WORK=$(mktemp -d "${TMPDIR:-/tmp}/easylab-sdcc.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
$APT source --download-only sdcc >> "$LOG" 2>&1 || fail "apt-get source sdcc failed (is there a deb-src entry?)"
dpkg-source -x sdcc_*.dsc src >> "$LOG" 2>&1 || fail "unpacking sdcc's source failed"
cd src
SOURCE_VERSION=$(dpkg-parsechangelog -S Version 2>/dev/null || echo unknown)
case $SOURCE_VERSION in
    "$SDCC_VERSION"*) ;;
    *) echo "note: Debian's sdcc source is $SOURCE_VERSION, not $SDCC_VERSION; trying anyway" >> "$LOG" ;;
esac

# ---- 2. configure: the pic16 port only, its libraries for the large stack model
sed -i 's/--fomit-frame-pointer/--pstack-model=large --fomit-frame-pointer/' \
    device/lib/pic16/Makefile.in device/lib/pic16/*/Makefile.in
grep -q "pstack-model=large" device/lib/pic16/libsdcc/Makefile.in || fail "the library flags were not found"
mkdir -p device/non-free/lib/pic16
for f in supported-devices.ac processors.ac; do
    : > "device/non-free/lib/pic16/$f"
    touch -d 2000-01-01 "device/non-free/lib/pic16/$f"
done
./configure --prefix="$PREFIX" --disable-mcs51-port --disable-z80-port --disable-z180-port --disable-r2k-port \
    --disable-r2ka-port --disable-r3ka-port --disable-sm83-port --disable-tlcs90-port --disable-ez80_z80-port \
    --disable-z80n-port --disable-ds390-port --disable-ds400-port --disable-pic14-port --disable-hc08-port \
    --disable-s08-port --disable-stm8-port --disable-pdk13-port --disable-pdk14-port --disable-pdk15-port \
    --disable-mos6502-port --disable-ucsim --disable-sdcdb --disable-non-free >> "$LOG" 2>&1 \
    || fail "configuring sdcc failed"

# ---- 3. build and install (the autotools are never rerun)
NOAUTO="ACLOCAL=true AUTOCONF=true AUTOHEADER=true AUTOMAKE=true"
# shellcheck disable=SC2086
make -j"$(nproc)" $NOAUTO >> "$LOG" 2>&1 || fail "building sdcc failed"
# shellcheck disable=SC2086
make install $NOAUTO >> "$LOG" 2>&1 || fail "installing sdcc failed"
[ -f "$PREFIX/share/sdcc/lib/pic16/libc18f.lib" ] || fail "the pic16 libraries were not built"
rm -rf "$PREFIX/share/sdcc/lib/src"

# ---- 4. device headers and libraries
INC=$PREFIX/share/sdcc/include/pic16
LIB=$PREFIX/share/sdcc/lib/pic16
python3 "$HERE/device_headers.py" /usr/share/gputils/header "$INC" $PARTS >> "$LOG" 2>&1 \
    || fail "generating the device headers failed"
for part in $PARTS; do
    "$PREFIX/bin/sdcc" -mpic16 -p"$part" --no-warn-non-free -c "$INC/pic$part.c" -o "$WORK/pic$part.o" \
        >> "$LOG" 2>&1 || fail "compiling the device library of the $part failed"
    rm -f "$LIB/libdev$part.lib"
    gplib -c "$LIB/libdev$part.lib" "$WORK/pic$part.o" >> "$LOG" 2>&1 || fail "archiving libdev$part.lib failed"
    rm -f "$INC/pic$part.c"
done

printf 'sdcc %s (pic16 port, recipe %s) from Debian source %s; parts %s\n' "$SDCC_VERSION" "$RECIPE" \
    "$SOURCE_VERSION" "$PARTS" > "$STAMP"
echo "sdcc's pic16 port is ready in $PREFIX"
