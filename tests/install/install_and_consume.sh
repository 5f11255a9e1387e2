#!/bin/sh
# Installs the build into a staging folder (DESTDIR) and builds a consumer project against
# the installed Darkroom package; checks what was installed and that the consumer runs.
#   install_and_consume.sh BUILD_DIR SOURCE_DIR SCRATCH_DIR
set -eu
build=$1 source=$2 scratch=$3
rm -rf "$scratch" && mkdir -p "$scratch"
DESTDIR="$scratch/root" cmake --install "$build" --prefix /usr/local > "$scratch/install.log"
root="$scratch/root"
for path in usr/local/bin/darkroom usr/local/include/darkroom/core/develop.h \
            usr/local/lib/cmake/Darkroom/DarkroomConfig.cmake usr/local/share/doc/darkroom/LICENSE \
            usr/OFX/Plugins/Darkroom.ofx.bundle/Contents/Linux-x86-64/Darkroom.ofx; do
  [ -e "$root/$path" ] || { echo "not installed: /$path"; exit 1; }
done
ls "$root"/usr/local/lib/python3.*/dist-packages/darkroom*.so > /dev/null || { echo "no Python module installed"; exit 1; }
"$root/usr/local/bin/darkroom" --version
cmake -S "$source/tests/install/consumer" -B "$scratch/consumer" -DCMAKE_PREFIX_PATH="$root/usr/local" \
      -DCMAKE_BUILD_TYPE=Release > "$scratch/configure.log"
cmake --build "$scratch/consumer" > "$scratch/build.log"
"$scratch/consumer/consumer" > "$scratch/print.txt"
# The print's green rises with each stop of exposure (a ramp over 8 stops round mid grey).
sort -g -c "$scratch/print.txt" || { echo "the consumer's print does not rise:"; cat "$scratch/print.txt"; exit 1; }
[ "$(sort -u "$scratch/print.txt" | wc -l)" -eq 8 ] || { echo "the consumer's print is not a ramp"; exit 1; }
echo "installed, and a consumer built against the package develops a ramp"
