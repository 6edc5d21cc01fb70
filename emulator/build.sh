#!/bin/sh
# sh build.sh: build the emulator into bin/emulator (Go 1.22+; standard library and ../clients/generated/go only).
set -e
cd "$(dirname "$0")"
export GOTOOLCHAIN="${GOTOOLCHAIN:-local}"
[ -n "$GOCACHE" ] || [ -n "$HOME" ] || export GOCACHE="${TMPDIR:-/tmp}/go-build-cache"
go build -o bin/emulator ./cmd/emulator
