#!/usr/bin/env bash
# test_docs_examples.sh SOURCE_DIR BIN_DIR -- runs every command of the ```sh blocks of README.md's
# neighbours docs/*.md (issue 6: "docs examples that contain commands are run by a test, so they
# cannot rot").  Each docs file runs in its own scratch directory, its blocks in order, one
# command per line (lines ending in '\' continue), with BIN_DIR (the build's mfkit) first on PATH
# and ../shared linked to the source tree's ../shared.  A command whose comment says "fails"
# must exit 1; every other command must exit 0.  Blocks marked ```sh norun are skipped (they say
# why); a command that uses ../shared is skipped, with a message, when that directory is absent.
set -u
src=$1 bin=$2
fails=0 runs=0 skips=0
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_docs.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
shared=$(cd "$src/.." && pwd)/shared
export PATH="$bin:$PATH"
for doc in "$src"/docs/*.md; do
    name=$(basename "$doc" .md)
    work="$tmp/$name/work"
    mkdir -p "$work"
    [ -d "$shared" ] && ln -s "$shared" "$tmp/$name/shared"
    # the commands, continuation lines joined, one per line
    awk '/^```sh *$/{p=1;next} /^```/{p=0} p' "$doc" |
        awk '{ if (sub(/\\$/, "")) { buf = buf $0; next } print buf $0; buf = "" }' >"$tmp/$name.cmds"
    while IFS= read -r cmd; do
        case "$cmd" in ''|'#'*) continue ;; esac
        if [[ "$cmd" == *"../shared"* ]] && ! [ -d "$shared" ]; then
            echo "SKIP ($name): $cmd (no $shared)"; skips=$((skips+1)); continue
        fi
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
echo "test_docs_examples: $runs commands run, $fails failed, $skips skipped"
[ $runs -gt 0 ] && [ $fails -eq 0 ]
