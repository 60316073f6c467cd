# Sourced by the benchmark scripts under tests/benchmarks: what they all do before their work,
# i.e. the help text, argument parsing, error exit and the checks of the build folder.
#
#   source "$(dirname "${BASH_SOURCE[0]}")/../lib/common.sh"
#
# Sets `root` (the source tree), `build` (the default build folder, root/build) and `kg_name`
# (the calling script's file name, for messages). A script's help text is its header comment:
# from line 2 to the line before its `set -` line; a script whose first argument is --help / -h
# prints it and exits 0 here, when it sources this file (sourced without arguments, this file
# sees the script's).

kg_name="$(basename "$0")"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
build="$root/build"

# die MESSAGE...: "SCRIPT: error: MESSAGE" on stderr, exit status 2.
die() { echo "$kg_name: error: $*" >&2; exit 2; }

# kg_usage: the calling script's header comment without its leading '# '.
kg_usage() { sed -n '2,/^set -/p' "$0" | sed '$d; s/^# \{0,1\}//'; }

# The script's arguments: a first --help / -h prints the help text.
case "${1:-}" in --help|-h) kg_usage; exit 0 ;; esac

# kg_parse_args SPEC... -- ARGS...: parses ARGS into the caller's variables. A SPEC is
# OPTION=VARIABLE for an option followed by a value (`--out=out`: `--out DIR` sets $out) or
# OPTION=VARIABLE:VALUE for a flag (`--map=withMap:1`: `--map` sets $withMap to 1).
# --help / -h prints kg_usage and exits 0; an unknown option or a missing value dies.
kg_parse_args() {
  local -A _kg_value=() _kg_flag=()
  while [ $# -gt 0 ] && [ "$1" != -- ]; do
    case "$1" in
      *=*:*) _kg_flag["${1%%=*}"]="${1#*=}" ;;
      *=*) _kg_value["${1%%=*}"]="${1#*=}" ;;
      *) die "kg_parse_args: bad option spec '$1'" ;;
    esac
    shift
  done
  [ $# -gt 0 ] || die "kg_parse_args: no '--' before the arguments"
  shift
  while [ $# -gt 0 ]; do
    case "$1" in
      --help|-h) kg_usage; exit 0 ;;
      "") die "empty argument (see --help)" ;;
    esac
    if [ -n "${_kg_flag[$1]+set}" ]; then
      printf -v "${_kg_flag[$1]%%:*}" '%s' "${_kg_flag[$1]#*:}"
      shift
      continue
    fi
    [ -n "${_kg_value[$1]+set}" ] || die "unknown argument '$1' (see --help)"
    [ $# -ge 2 ] || die "missing value after $1"
    printf -v "${_kg_value[$1]}" '%s' "$2"
    shift 2
  done
}

# kg_build_dir DIR TOOL...: prints DIR as an absolute path after checking that DIR/bin/TOOL is an
# executable for every TOOL. Use: build="$(kg_build_dir "$build" keygrid-slam)" || exit 2
kg_build_dir() {
  local dir t
  dir="$(cd "$1" 2>/dev/null && pwd)" || die "no build folder $1"
  shift
  for t in "$@"; do
    [ -x "$dir/bin/$t" ] || die "$dir/bin/$t not found (build it, or name another build folder)"
  done
  echo "$dir"
}

# kg_whole_number OPTION VALUE: dies unless VALUE is a whole number.
kg_whole_number() { [[ "$2" =~ ^[0-9]+$ ]] || die "$1 must be a whole number, got '$2'"; }
