#!/usr/bin/env bash
# The layering of docs/design.md, checked on every include: dfb/ includes nothing of ours;
# renderers/ and wall/ use dfb/ but not each other (nor apps/); only apps/ ties them together.
# (Includes are written from the repository root, so one include path serves every library;
# this test is what keeps a library from reaching into another.)
set -euo pipefail
root=$1
status=0
forbid() {  # forbid FOLDER PATTERN...
  local folder=$1; shift
  for other in "$@"; do
    if hits=$(grep -rnE "#include +\"$other/" "$root/$folder" --include='*.h' --include='*.cpp'); then
      echo "FAIL: $folder/ must not include $other/:"; echo "$hits"; status=1
    fi
  done
}
forbid dfb renderers wall apps
forbid renderers wall apps
forbid wall renderers apps
[ $status -eq 0 ] && echo "dfb/ -> nothing; renderers/, wall/ -> dfb/ only: holds"
exit $status
