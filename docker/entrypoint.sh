#!/bin/sh
# The image's entry point: runs its command (CMD, or the one `docker run IMAGE ...` gives)
# once Numba can open its cache.
#
# Numba opens a cache only in a directory it can write to, even just to load what is there:
# with a read-only root (`docker run --read-only`, compose `read_only: true`) the cache
# baked into the image at NUMBA_CACHE_DIR would be refused ("cannot cache function ...: no
# locator available") and every kernel compiled again (minutes). So when NUMBA_CACHE_DIR
# is not writable, a writable copy is made in the temporary directory (a tmpfs): a tree of
# links to the baked files, so nothing is copied or compiled, and a kernel compiled later
# (a new type) is written beside them. Without a writable /tmp, /dev/shm serves.
set -eu
if [ -n "${NUMBA_CACHE_DIR:-}" ] && [ -d "$NUMBA_CACHE_DIR" ] && [ ! -w "$NUMBA_CACHE_DIR" ]; then
    if [ ! -w "${TMPDIR:-/tmp}" ] && [ -w /dev/shm ]; then
        export TMPDIR=/dev/shm
    fi
    writable="${TMPDIR:-/tmp}/numba-cache"
    if [ ! -d "$writable" ]; then
        mkdir -p "$writable.part"
        cp -Rs "$NUMBA_CACHE_DIR/." "$writable.part/"
        mv "$writable.part" "$writable"
    fi
    export NUMBA_CACHE_DIR="$writable"
fi
exec "$@"
