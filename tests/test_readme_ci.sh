#!/usr/bin/env bash
# test_readme_ci.sh SRC -- .ci/run runs exactly README's test command (the line after the
# marker <!-- test-command --> in README.md's fenced block), so the two cannot drift apart.
set -eu
src="$1"
readme_cmd=$(awk '/<!-- test-command -->/{f=1; next} f && /^```/{if (g) exit; g=1; next} f && g {print}' "$src/README.md")
ci_cmd=$(awk '/^# README test command/{f=1; next} f {print; exit}' "$src/.ci/run")
if [ -z "$readme_cmd" ] || [ "$readme_cmd" != "$ci_cmd" ]; then
  echo "README test command and .ci/run differ:"; echo "README: $readme_cmd"; echo "CI:     $ci_cmd"
  echo "test_readme_ci: 0 passed, 1 failed"; exit 1
fi
echo "test_readme_ci: 1 passed, 0 failed"
