#!/usr/bin/env bash
# test_standalone.sh SOURCE_DIR -- the repository stands alone: no tracked file points at material
# that exists only beside a checkout, and every vendored data file carries its license.
#
# 1. Pointers out of the tree.  Every file of the source tree (`git ls-files` when SOURCE_DIR is a
#    git checkout, else every regular file found under it, the build directories and .git
#    excluded) is searched for the parent-directory notes folder, the name of the notes file of
#    paper corrections, and paper files by their number.  Papers are cited by authors, year and
#    equation; corrections to printed formulas by docs/math.md item (C-L2, ...).  The patterns are
#    assembled from pieces below, so this file does not match them itself.
# 2. tests/data/reference: every data file has a license file beside it (PREFIX_LICENSE.txt, where
#    PREFIX_ starts the data file's name), README.md names it, and in a git checkout it is tracked
#    (a file present only in one working tree would make the tests pass there and fail elsewhere).
# Before checking the source tree, both checks run on a scratch tree with one planted defect of
# each kind and must report them (a negative control: the checks can fail).
set -u
src=$(cd "${1:?usage: test_standalone.sh SOURCE_DIR}" && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_standalone.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT

up='..'
pat_notes_dir="$up/sha""red"
pat_notes_file="ERR""ATA"
pat_papers="papers/""00[0-4]"
pattern="(\\.\\./sha""red|$pat_notes_file|$pat_papers)"

# list_files DIR: the files to search, one per line, relative to DIR
list_files() {
    if [ -e "$1/.git" ] && git -C "$1" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
        git -C "$1" ls-files
    else
        (cd "$1" && find . -path ./.git -prune -o -path './build*' -prune -o -type f -print | sed 's|^\./||')
    fi
}

# pointers DIR: prints FILE:LINE: TEXT for every match; exit 0 if there is none
pointers() {
    local dir=$1 bad=0 f m
    while IFS= read -r f; do
        [ -f "$dir/$f" ] || continue
        m=$(grep -IEn "$pattern" "$dir/$f" 2>/dev/null)
        if [ -n "$m" ]; then
            printf '%s\n' "$m" | sed "s|^|$f:|"
            bad=1
        fi
    done < <(list_files "$dir")
    return $bad
}

# licenses DIR: prints one line per vendored file without a license, unnamed by README.md, or
# untracked in a git checkout; exit 0 if there is none
licenses() {
    local dir=$1 ref=$1/tests/data/reference bad=0 f name lic ok tracked=
    [ -d "$ref" ] || { echo "tests/data/reference: missing"; return 1; }
    [ -f "$ref/README.md" ] || { echo "tests/data/reference/README.md: missing"; bad=1; }
    if [ -e "$dir/.git" ] && git -C "$dir" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
        tracked=$(git -C "$dir" ls-files tests/data/reference)
    fi
    for f in "$ref"/*; do
        name=$(basename "$f")
        case "$name" in README.md|*_LICENSE.txt) continue ;; esac
        ok=0
        for lic in "$ref"/*_LICENSE.txt; do
            [ -f "$lic" ] || continue
            lic=$(basename "$lic" _LICENSE.txt)
            case "$name" in "${lic}_"*) ok=1 ;; esac
        done
        [ $ok -eq 1 ] || { echo "tests/data/reference/$name: no PREFIX_LICENSE.txt beside it"; bad=1; }
        grep -qF "$name" "$ref/README.md" 2>/dev/null ||
            { echo "tests/data/reference/$name: not described in tests/data/reference/README.md"; bad=1; }
        if [ -e "$dir/.git" ] && ! printf '%s\n' "$tracked" | grep -qxF "tests/data/reference/$name"; then
            echo "tests/data/reference/$name: not tracked by git"; bad=1
        fi
    done
    return $bad
}

fail=0
# Negative control: a scratch tree (no .git) with one defect of each kind.
neg=$tmp/neg
mkdir -p "$neg/tests/data/reference" "$neg/lib"
printf 'see %s/reference/x.csv\n' "$pat_notes_dir" >"$neg/lib/a.c"
printf '/* %s L3 */\n' "$pat_notes_file" >"$neg/lib/b.h"
printf 'papers/%s_x.txt\n' "003" >"$neg/c.md"
printf 'nothing to see\n' >"$neg/d.md"
printf 'x\n' >"$neg/tests/data/reference/foo_table.csv"
printf 'x\n' >"$neg/tests/data/reference/bar_table.csv"
printf 'license\n' >"$neg/tests/data/reference/foo_LICENSE.txt"
printf 'foo_table.csv\n' >"$neg/tests/data/reference/README.md"
out=$(pointers "$neg") && { echo "FAIL: negative control: planted pointers not found"; fail=1; }
for f in lib/a.c lib/b.h c.md; do
    printf '%s\n' "$out" | grep -q "^$f:1:" || { echo "FAIL: negative control: $f not reported ($out)"; fail=1; }
done
! printf '%s\n' "$out" | grep -q '^d.md' || { echo "FAIL: negative control: clean d.md reported"; fail=1; }
out=$(licenses "$neg") && { echo "FAIL: negative control: the unlicensed file was not found"; fail=1; }
printf '%s\n' "$out" | grep -q 'bar_table.csv: no PREFIX_LICENSE.txt' ||
    { echo "FAIL: negative control: bar_table.csv's missing license not reported ($out)"; fail=1; }
printf '%s\n' "$out" | grep -q 'bar_table.csv: not described' ||
    { echo "FAIL: negative control: bar_table.csv missing from README.md not reported ($out)"; fail=1; }
! printf '%s\n' "$out" | grep -q 'foo_table.csv' || { echo "FAIL: negative control: foo_table.csv reported ($out)"; fail=1; }

# The source tree.
n=$(list_files "$src" | wc -l)
[ "$n" -gt 0 ] || { echo "FAIL: no files listed under $src"; fail=1; }
if ! out=$(pointers "$src"); then
    echo "FAIL: files point outside the repository (cite papers by authors, year and equation, and"
    echo "      corrections as docs/math.md items; vendor data into tests/data with its license):"
    printf '%s\n' "$out" | sed 's/^/    /'
    fail=1
fi
if ! out=$(licenses "$src"); then
    echo "FAIL: vendored reference data:"
    printf '%s\n' "$out" | sed 's/^/    /'
    fail=1
fi
[ $fail -eq 0 ] && echo "test_standalone: OK ($n files searched; tests/data/reference licensed and described)"
exit $fail
