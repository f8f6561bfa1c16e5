#!/usr/bin/env bash
# Moved to device/gpu_check.sh (device tooling, issue 46); kept so that `bash bench/gpu_check.sh` still works.
exec bash "$(dirname "$0")/../device/gpu_check.sh" "$@"
