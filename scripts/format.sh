#!/usr/bin/env bash
# Format flowire's C++ sources with clang-format and the tree's .clang-format (Google style,
# 120 columns). With --check nothing is changed: the files that would change are listed and
# the script fails (the default tests run it as `format_check`).
# Usage: scripts/format.sh [--check]   (CLANG_FORMAT=path: which clang-format to use)
set -euo pipefail
cd "$(dirname "$0")/.."
CHECK=0
case "${1:-}" in
  --check) CHECK=1 ;;
  "") ;;
  -h | --help) sed -n '2,5p' "$0"; exit 0 ;;
  *) echo "format.sh: error: unknown argument '$1' (see --help)" >&2; exit 2 ;;
esac
CF=${CLANG_FORMAT:-$(command -v clang-format-14 || command -v clang-format || true)}
if [ -z "$CF" ]; then
  # FORMAT_MISSING_STATUS: the test run's skip status (the check is skipped, saying why).
  echo "format.sh: error: clang-format not found (Debian: apt-get install clang-format)" >&2
  exit "${FORMAT_MISSING_STATUS:-2}"
fi
mapfile -t FILES < <(find common vessels mesh solid flow rod coupling tools tests bench python \
  \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) -type f | sort)
if [ "$CHECK" = 0 ]; then
  "$CF" -i "${FILES[@]}"
  exit 0
fi
BAD=()
for f in "${FILES[@]}"; do
  if ! "$CF" --dry-run --Werror "$f" >/dev/null 2>&1; then BAD+=("$f"); fi
done
if [ ${#BAD[@]} -gt 0 ]; then
  printf 'format.sh: %s\n' "${BAD[@]}" >&2
  echo "format.sh: ${#BAD[@]} of ${#FILES[@]} files are not formatted: run scripts/format.sh" >&2
  exit 1
fi
echo "format.sh: ${#FILES[@]} files formatted"
