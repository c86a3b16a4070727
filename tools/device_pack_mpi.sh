#!/bin/bash
# The distributed world's runs for the lent 16-core machine (issue #30: MPI x threads on real
# cores). Run after ../shared/device/pack.sh, from the project root:
#   tools/quadrant build release && ../shared/device/pack.sh && tools/device_pack_mpi.sh
# Adds to .device/: quadrant_distributed and quadrant_task_overhead; Open MPI's launcher, daemon, components and help text
# under .device/mpi/ (the lent machine has no Open MPI; OPAL_PREFIX relocates it there); every
# shared library these need outside glibc into .device/lib/; and distributed.sh, the runs
# themselves (tools/device_distributed.sh). About 20 MB more; the lent machine then runs
#   bash .device/scaling.sh quick; bash .device/distributed.sh      (carry [".device"])
set -euo pipefail
bin=${1:-build/release/benchmarks/quadrant_distributed}
die() { echo "device_pack_mpi: $*" >&2; exit 2; }
[ -x "$bin" ] || die "$bin is not an executable (build the release preset first)"
[ -d .device/lib ] || die "no .device/lib: run ../shared/device/pack.sh first"
command -v ompi_info >/dev/null || die "ompi_info not found (openmpi-bin)"
here=$(cd "$(dirname "$0")" && pwd)
# Open MPI's own directories, as this installation names them (Debian: prefix /usr).
path() { ompi_info --path "$1" --parsable | sed -n "s/^path:$1://p"; }
prefix=$(path prefix)
pkglibdir=$(path pkglibdir)
pkgdatadir=$(path pkgdatadir)
bindir=$(path bindir)
[[ -n "$prefix" && "$pkglibdir" == "$prefix"/* && "$pkgdatadir" == "$prefix"/* ]] ||
  die "Open MPI's directories are not under its prefix ($prefix): cannot relocate it"
m=.device/mpi
rm -rf "$m" && mkdir -p "$m/bin" "$m${pkglibdir#"$prefix"}" "$m${pkgdatadir#"$prefix"}"
cp "$bin" .device/quadrant_distributed
# The pool's cost per call and per stage at 1-16 threads (distributed.sh runs it first).
overhead=$(dirname "$bin")/quadrant_task_overhead
[ -x "$overhead" ] || die "$overhead is not an executable (build the release preset first)"
cp "$overhead" .device/quadrant_task_overhead
cp -L "$bindir/orterun" "$bindir/orted" "$m/bin/"
ln -s orterun "$m/bin/mpirun"
cp -L "$pkglibdir"/*.so "$m${pkglibdir#"$prefix"}/"
cp -rL "$pkgdatadir"/. "$m${pkgdatadir#"$prefix"}/"
# PMIx (Debian builds Open MPI 4 against libpmix2): its components, relocated by PMIX_INSTALL_PREFIX.
pmix=""
for d in /usr/lib/x86_64-linux-gnu/pmix2 /usr/lib/x86_64-linux-gnu/pmix; do
  [ -d "$d/lib/pmix" ] && { pmix=$d; break; }
done
if [ -n "$pmix" ]; then
  mkdir -p "$m/pmix/lib/pmix"
  cp -L "$pmix"/lib/pmix/*.so "$m/pmix/lib/pmix/"
  [ -d "$pmix/share/pmix" ] && mkdir -p "$m/pmix/share" && cp -rL "$pmix/share/pmix" "$m/pmix/share/"
fi
# Every library the binaries and components resolve outside glibc's own set.
for f in "$bin" "$overhead" "$m"/bin/orterun "$m"/bin/orted "$m${pkglibdir#"$prefix"}"/*.so ${pmix:+"$m"/pmix/lib/pmix/*.so}; do
  ldd "$f" | awk '/=> \//{print $3}'
done | sort -u | while read -r lib; do
  case "$(basename "$lib")" in libc.so*|libm.so*|ld-linux*|libpthread*|libdl.so*|librt.so*) ;; *) cp -Ln "$lib" .device/lib/ ;; esac
done
cp "$here/device_distributed.sh" .device/distributed.sh
echo "packed Open MPI and quadrant_distributed: .device is now $(du -sh .device | cut -f1)"
