#!/usr/bin/env bash
# test_model_list.sh MFKIT DOCS_CLI_MD -- the model list of docs/cli.md (between the markers
# "<!-- models: mfkit fit ltc --list -->" and "<!-- /models -->") names the registered models of
# `mfkit fit ltc --list`, in its order; every --list line is "name<TAB>description".
set -u
mfkit=$1
doc=$2
list=$("$mfkit" fit ltc --list) || { echo "FAIL: mfkit fit ltc --list exited $?"; exit 1; }
bad=$(printf '%s\n' "$list" | awk -F'\t' 'NF != 2 || $1 !~ /^[a-z0-9-]+$/ || $2 == ""')
if [ -n "$bad" ]; then
    echo "FAIL: --list lines not 'name<TAB>description':"; printf '%s\n' "$bad"; exit 1
fi
from_cli=$(printf '%s\n' "$list" | cut -f1)
from_doc=$(sed -n '/<!-- models: mfkit fit ltc --list -->/,/<!-- \/models -->/p' "$doc" |
           sed -n 's/^| `\([a-z0-9-]*\)` |.*/\1/p')
if [ -z "$from_doc" ]; then
    echo "FAIL: $doc: no model list between the markers"; exit 1
fi
if [ "$from_cli" != "$from_doc" ]; then
    echo "FAIL: $doc lists other models than 'mfkit fit ltc --list'"
    echo "--- mfkit fit ltc --list"; printf '%s\n' "$from_cli"
    echo "--- $doc"; printf '%s\n' "$from_doc"
    exit 1
fi
echo "model list: $(printf '%s ' $from_cli)(docs/cli.md agrees)"
