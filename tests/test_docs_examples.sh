#!/usr/bin/env bash
# test_docs_examples.sh SOURCE_DIR BIN_DIR -- runs every command of the ```sh blocks of README.md's
# neighbours docs/*.md (issue 6: "docs examples that contain commands are run by a test, so they
# cannot rot").  Each docs file runs in its own scratch directory, its blocks in order, one
# command per line (lines ending in '\' continue), with BIN_DIR (the build's mfkit) first on PATH
# and tests/data/reference (the vendored reference tables, so the commands read as if run from the
# checkout's root) linked to the source tree's.  A command whose comment says "fails" must exit 1;
# every other command must exit 0.  Blocks marked ```sh norun are skipped (they say why); nothing
# else is skipped: a missing vendored file makes the test fail.
set -u
src=$1 bin=$2
fails=0 runs=0
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_docs.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
reference=$(cd "$src" && pwd)/tests/data/reference
[ -f "$reference/ltc_code_ggx_64.csv" ] || { echo "test_docs_examples: FAIL: the vendored reference tables are missing ($reference)"; exit 1; }
export PATH="$bin:$PATH"
for doc in "$src"/docs/*.md; do
    name=$(basename "$doc" .md)
    work="$tmp/$name/work"
    mkdir -p "$work"
    mkdir -p "$work/tests/data" && ln -s "$reference" "$work/tests/data/reference"
    # the commands, continuation lines joined, one per line
    awk '/^```sh *$/{p=1;next} /^```/{p=0} p' "$doc" |
        awk '{ if (sub(/\\$/, "")) { buf = buf $0; next } print buf $0; buf = "" }' >"$tmp/$name.cmds"
    while IFS= read -r cmd; do
        case "$cmd" in ''|'#'*) continue ;; esac
        want=0
        [[ "$cmd" == *"# fails"* ]] && want=1
        (cd "$work" && bash -c "$cmd") >"$tmp/out.log" 2>&1 </dev/null; rc=$?
        runs=$((runs+1))
        if [ $rc -ne $want ]; then
            echo "FAIL ($name): exit $rc, expected $want: $cmd"; sed 's/^/    /' "$tmp/out.log" | tail -n 8
            fails=$((fails+1))
        else
            echo "ok   ($name): $cmd"
        fi
    done <"$tmp/$name.cmds"
done
echo "test_docs_examples: $runs commands run, $fails failed"
[ $runs -gt 0 ] && [ $fails -eq 0 ]
