#!/usr/bin/env bash
# Checks the folder layers (cmake/layers.txt) against the source tree:
#   - every folder in layers.txt names only folders declared above it (so the declared graph has no cycle);
#   - every top-level folder holding .h/.cpp files is either a layer or a consumer (tests, bench, fuzz);
#   - every #include "folder/..." in a layer folder names the folder itself or one it may include (the closure
#     of what layers.txt says it builds on); no include climbs out with "../".
# Prints each violation as FILE:LINE: message and exits 1 if there is any. Needs only bash, grep and sed, so CI
# and a fresh machine can run it before anything is built: `bash scripts/check_layers.sh`.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
LAYERS_FILE=cmake/layers.txt
CONSUMERS=(tests bench fuzz)

declare -A direct=()   # folder -> space-separated folders it builds on
declare -A allowed=()  # folder -> closure of `direct`, with the folder itself
order=()
errors=0
fail() { echo "$1" >&2; errors=$((errors + 1)); }

lineno=0
while IFS= read -r line || [ -n "$line" ]; do
  lineno=$((lineno + 1))
  line="${line%%#*}"
  [[ "$line" =~ ^[[:space:]]*$ ]] && continue
  if [[ ! "$line" =~ ^([a-z_]+):(.*)$ ]]; then
    fail "$LAYERS_FILE:$lineno: expected 'folder: folders it builds on', got '$line'"
    continue
  fi
  name="${BASH_REMATCH[1]}"
  deps="${BASH_REMATCH[2]}"
  if [ -n "${direct[$name]+x}" ]; then
    fail "$LAYERS_FILE:$lineno: folder '$name' declared twice"
    continue
  fi
  [ -d "$name" ] || fail "$LAYERS_FILE:$lineno: folder '$name' does not exist"
  closure=" $name "
  for dep in $deps; do
    if [ -z "${direct[$dep]+x}" ]; then
      # Only folders declared above may be named: that is what keeps the folder graph acyclic.
      fail "$LAYERS_FILE:$lineno: '$name' builds on '$dep', which is not declared above it"
      continue
    fi
    for d in ${allowed[$dep]}; do
      [[ "$closure" == *" $d "* ]] || closure+="$d "
    done
  done
  direct[$name]="$deps"
  allowed[$name]="$closure"
  order+=("$name")
done < "$LAYERS_FILE"

# Every folder with sources is accounted for.
for dir in */; do
  dir="${dir%/}"
  [ -n "${direct[$dir]+x}" ] && continue
  [[ " ${CONSUMERS[*]} " == *" $dir "* ]] && continue
  [[ "$dir" == build* ]] && continue
  if find "$dir" -name '*.h' -o -name '*.cpp' | grep -q .; then
    fail "$dir/: has C++ sources but is neither a layer in $LAYERS_FILE nor a consumer (${CONSUMERS[*]})"
  fi
done

checked=0
for folder in "${order[@]}"; do
  while IFS= read -r file; do
    while IFS=: read -r ln text; do
      checked=$((checked + 1))
      target="$(sed -E 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"([^"]*)".*/\1/' <<<"$text")"
      if [[ "$target" == ../* || "$target" == */../* ]]; then
        fail "$file:$ln: include climbs out of the layers: \"$target\""
        continue
      fi
      [[ "$target" == */* ]] || continue       # a sibling header, found beside the file
      to="${target%%/*}"
      [ -n "${direct[$to]+x}" ] || continue     # not a layer folder (e.g. a generated or system path)
      if [[ "${allowed[$folder]}" != *" $to "* ]]; then
        fail "$file:$ln: '$folder' may not include '$target' ($folder builds on:${allowed[$folder]% }; see $LAYERS_FILE)"
      fi
    done < <(grep -nE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$file" || true)
  done < <(find "$folder" \( -name '*.h' -o -name '*.cpp' \) | sort)
done

if [ "$errors" -gt 0 ]; then
  echo "check_layers: $errors violation(s)" >&2
  exit 1
fi
echo "check_layers: ${#order[@]} layers (${order[*]}), $checked includes checked, no violation, no folder cycle"
