#!/usr/bin/env bash
# The layering of docs/design.md, checked on every include: base/ includes nothing of ours;
# messaging/ only base/; dfb/ uses messaging/ only; renderers/ and wall/ use dfb/ and messaging/
# but not each other (nor runtime/, apps/, api/); runtime/ ties them together for apps/ and api/
# (the data-distributed API), which compose runtime/ and neither
# includes the other; bench/ and examples/ never include tests/.
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
forbid base messaging dfb renderers wall runtime apps api
forbid messaging dfb renderers wall runtime apps api
forbid dfb renderers wall runtime apps api
forbid renderers wall runtime apps api
forbid wall renderers runtime apps api
forbid runtime apps api
forbid api apps
forbid apps api
# Benchmarks and examples use what a user could: never the tests' helpers.
forbid bench tests
forbid examples tests
# The API's public header is all an installed program sees: MPI and the standard library only.
if hits=$(grep -nE '#include +"' "$root/api/DataDistributed.h"); then
  echo "FAIL: api/DataDistributed.h must include only <mpi.h> and standard headers:"; echo "$hits"
  status=1
fi
[ $status -eq 0 ] && echo "base/ -> nothing; messaging/ -> base/ only; dfb/ -> messaging/ only; renderers/, wall/ -> dfb/, messaging/ only; runtime/ -> no apps/, api/; api/ self-contained; bench/, examples/ -> no tests/: holds"
exit $status
