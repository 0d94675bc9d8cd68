#!/usr/bin/env bash
# The GPU measurements on a lent GPU machine (README, "Development"), from the project
# root: install the wheels carried in .whl/ (that machine reaches no package index),
# register NVIDIA's OpenCL driver, run benchmarks/gpu.py (every workload on Numba and
# OpenCL, the calibration, profiles), the OpenCL tests on the GPU, then the cold start
# last (its children compile every kind with empty caches: the longest, least needed part).
# Results: $OUT/bench.log, $OUT/gpu*.json, $OUT/tests.log, $OUT/cold.log.
# A short rerun: BENCH_ARGS="--only segments,windows --skip-sweeps" TESTS=0 COLD=0.
set -u
export PYTHONUNBUFFERED=1
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH=/tmp/site:$PWD
mkdir -p /tmp/vendors
lib=$(ls /usr/local/nvidia/lib64/libnvidia-opencl.so* /usr/lib/x86_64-linux-gnu/libnvidia-opencl.so* 2>/dev/null | head -1)
[[ -n $lib ]] && echo "$lib" > /tmp/vendors/nvidia.icd
export OCL_ICD_VENDORS=/tmp/vendors RNSCA_CACHE_DIR=/tmp/rnsca-cache
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
echo "cores $(nproc)"
quiet() { grep -v -i "warn\|_create_built\|prg.build"; }
timeout ${BENCH_TIMEOUT:-280} python3 -m benchmarks.gpu ${BENCH_ARGS:---profile --only segments,windows,lines,polygons,curves} 2>&1 | quiet | tee "$OUT/bench.log"
cp "$OUT/gpu.json" "$OUT/gpu-workloads.json" 2>/dev/null
[[ ${TESTS:-1} == 1 ]] && timeout ${TEST_TIMEOUT:-110} python3 -m pytest -q -p no:cacheprovider -o addopts="-ra" \
  tests/unit/backends tests/unit/test_many_windows.py tests/property/test_geometry_backends_agree.py \
  tests/property/test_windows_backends_agree.py 2>&1 | tail -15 | tee "$OUT/tests.log"
[[ ${COLD:-1} == 1 ]] && timeout ${COLD_TIMEOUT:-140} python3 -m benchmarks.gpu --only cold-start --skip-calibration 2>&1 | quiet | tee "$OUT/cold.log"
cp "$OUT/gpu.json" "$OUT/gpu-cold.json" 2>/dev/null
ls -la "$OUT"
