#!/usr/bin/env bash
# The layering of docs/design.md ("Folders"), checked on every include.
#
# Top level: base/ includes nothing of ours; messaging/ only base/; dfb/ uses messaging/ only;
# renderers/ and wall/ use dfb/ and messaging/ but not each other (nor runtime/, apps/, api/);
# runtime/ ties them together for apps/ and api/ (the data-distributed API), which compose it and
# neither includes the other; bindings/ (C, Python) sees api/ alone; bench/ and examples/ never
# include tests/.
#
# Sub-folders: a folder's own files and each of its sub-folders (with everything below it) are
# the nodes of that folder's include graph; the graph must have no cycle, so every arrow between
# sibling sub-folders, and between a folder's own files and a sub-folder, goes one way. A
# folder's own files are what its sub-folders share (renderers/: the core) or what ties them
# together (renderers/scivis/: the scene-file sections and the registration).
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
forbid base messaging dfb renderers wall runtime apps api bindings
forbid messaging dfb renderers wall runtime apps api bindings
forbid dfb renderers wall runtime apps api bindings
forbid renderers wall runtime apps api bindings
forbid wall renderers runtime apps api bindings
forbid runtime apps api bindings
forbid api apps bindings
forbid apps api bindings
# Other languages see the data-distributed API only, as a program would.
forbid bindings base messaging dfb renderers wall runtime apps
# Benchmarks and examples use what a user could: never the tests' helpers.
forbid bench tests
forbid examples tests
# Namespaces follow folders: a sub-library's files open its namespace (or one beneath it), never
# their parent library's.
sublibrary() {  # sublibrary FOLDER NAMESPACE PARENT_NAMESPACE
  local folder=$1 ns=$2 parent=$3
  if hits=$(grep -rnE "^namespace ${parent}( |::)" "$root/$folder" --include='*.h' --include='*.cpp' |
            grep -vE ":namespace ${ns}( |::)"); then
    echo "FAIL: $folder/ must open namespace $ns (or one beneath it), not:"; echo "$hits"; status=1
  fi
}
sublibrary renderers/scivis renderers::scivis renderers
sublibrary renderers/picture renderers::picture renderers
sublibrary wall/service wall::service wall
# The renderers core reaches the scivis renderer through its registries only: its code (comments
# aside) never names it.
if hits=$(grep -niE 'scivis' "$root"/renderers/*.h "$root"/renderers/*.cpp |
          grep -vE '^[^:]+:[0-9]+:[[:space:]]*//' | grep -iE '^[^:]+:[0-9]+:([^/]|/[^/])*scivis'); then
  echo "FAIL: the renderers core names the scivis renderer:"; echo "$hits"; status=1
fi
# The API's public headers are all an installed program sees: MPI and the standard library only.
for header in api/DataDistributed.h bindings/c/dfbwall.h; do
  if hits=$(grep -nE '#include +"' "$root/$header"); then
    echo "FAIL: $header must include only <mpi.h> and standard headers:"; echo "$hits"
    status=1
  fi
done

# Our source folders: the top-level ones with a CMakeLists.txt in them or one level down (not
# build trees, which have a CMakeCache.txt).
sources=()
for d in "$root"/*/; do
  d=${d%/}; d=${d##*/}
  [[ -f $root/$d/CMakeCache.txt ]] && continue
  if [[ -n $(find "$root/$d" -maxdepth 2 -name CMakeLists.txt -print -quit) ]]; then
    sources+=("$d")
  fi
done
# Every include of one of our files as "FILE INCLUDED" (system headers are not in the tree).
includes=$(cd "$root" &&
  find "${sources[@]}" \( -name '*.h' -o -name '*.cpp' -o -name '*.cc' \) -type f | sort |
  while IFS= read -r f; do
    sed -nE 's/^[[:space:]]*#[[:space:]]*include[[:space:]]+"([^"]+)".*/\1/p' "$f" |
      while IFS= read -r inc; do if [[ -f $inc ]]; then echo "$f $inc"; fi; done
  done || true)
# The same between folders: "FROM TO".
edges=$(echo "$includes" | awk '{ a = $1; b = $2; sub("/[^/]*$", "", a); sub("/[^/]*$", "", b)
                                  print a, b }' | sort -u)
# node(d), for awk with p set: the node of folder p's graph that folder d belongs to (p itself, or
# p/child for anything in or below child; the root's nodes are the top folders), "-" outside p.
node_awk='
  function node(d,   rest, n) {
    if (p == "") { n = index(d, "/"); return n ? substr(d, 1, n - 1) : d }
    if (d == p) return p
    if (index(d, p "/") != 1) return "-"
    rest = substr(d, length(p) + 2); n = index(rest, "/")
    return p "/" (n ? substr(rest, 1, n - 1) : rest)
  }'

# For each folder P, the graph of P's own files (node "P") and its sub-folders (node "P/child",
# everything below it); tsort finds any cycle. The arrows that hold are printed.
arrows=""
folders=$(echo "$edges" | tr ' ' '\n' | sort -u |
          awk -F/ '{ p = $1; print p; for (i = 2; i <= NF; i++) { p = p "/" $i; print p } }' |
          sort -u)
for p in "" $folders; do
  level=$(echo "$edges" | awk -v p="$p" "$node_awk"'
    { a = node($1); b = node($2); if (a != "-" && b != "-" && a != b) print a, b }' | sort -u)
  [[ -n $level ]] || continue
  if ! cycle=$(echo "$level" | tsort 2>&1 >/dev/null) || [[ -n $cycle ]]; then
    members=$(echo "$cycle" | sed -n '/input contains a loop/d; s/^tsort: //p' | tr '\n' ' ')
    echo "FAIL: the folders in ${p:-the repository root}/ include each other in a cycle: $members"
    echo "$includes" | awk -v p="$p" -v members=" $members" "$node_awk"'
      { a = $1; b = $2; sub("/[^/]*$", "", a); sub("/[^/]*$", "", b)
        a = node(a); b = node(b)
        if (a == b || !index(members, " " a " ") || !index(members, " " b " ")) next
        if (!((a, b) in first)) { first[a, b] = $1 " includes " $2; order[++n] = a SUBSEP b }
        count[a, b]++ }
      END { for (i = 1; i <= n; i++) { split(order[i], ab, SUBSEP)
              more = count[ab[1], ab[2]] - 1
              print "  " ab[1] " -> " ab[2] ": " first[ab[1], ab[2]] \
                    (more ? " (and " more " more)" : "") } }'
    status=1
  elif [[ -n $p && $p != tests* && $p != bench* ]]; then
    arrows+="  ${p}/: $(echo "$level" | awk -v p="$p" '
      { a = ($1 == p) ? "(own files)" : substr($1, length(p) + 2)
        b = ($2 == p) ? "(own files)" : substr($2, length(p) + 2)
        if (!(a in to)) { order[++n] = a; to[a] = b } else to[a] = to[a] ", " b }
      END { for (i = 1; i <= n; i++)
              printf "%s%s -> %s", (i > 1 ? "; " : ""), order[i], to[order[i]]
            print "" }')"$'\n'
  fi
done

if [[ $status -eq 0 ]]; then
  echo "base/ -> nothing; messaging/ -> base/ only; dfb/ -> messaging/ only; renderers/, wall/ -> dfb/, messaging/ only; runtime/ -> no apps/, api/; api/ self-contained; bench/, examples/ -> no tests/: holds"
  echo "renderers/scivis/ in renderers::scivis, renderers/picture/ in renderers::picture, wall/service/ in wall::service; the renderers core names no scivis: holds"
  echo "no folder includes another in a cycle; the arrows between sub-folders:"
  printf '%s' "$arrows"
fi
exit $status
