#!/usr/bin/env bash
# test_readme_tutorial.sh SRC BUILD -- runs README's tutorial block (<!-- tutorial -->) as written,
# with ./build/ replaced by BUILD, the output folder `tut` by a scratch one, and a 12x12 table
# instead of 32x32 (same commands, faster).  Skips the plot step if /usr/bin/python3 lacks matplotlib.
set -u
src="$1"; build="$2"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
block=$(awk '/<!-- tutorial -->/{f=1; next} f && /^```/{if (g) exit; g=1; next} f && g {print}' "$src/README.md")
[ -n "$block" ] || { echo "no tutorial block in README.md"; echo "test_readme_tutorial: 0 passed, 1 failed"; exit 1; }
have_mpl=1
/usr/bin/python3 -c "import matplotlib, numpy" 2>/dev/null || have_mpl=0
fails=0; n=0
cd "$src"
while IFS= read -r line; do
  case "$line" in ''|'#'*) continue ;; esac
  if [ $have_mpl -eq 0 ] && echo "$line" | grep -q "plot.py"; then echo "skip (no matplotlib): $line"; continue; fi
  cmd=$(printf '%s' "$line" | sed -e "s#\./build/#$build/#g" -e "s#tut/#$tmp/tut/#g" -e "s#--out tut#--out $tmp/tut#g" \
        -e "s#plot.py tut #plot.py $tmp/tut #g" -e "s#--size 32#--size 12#g")
  n=$((n+1))
  if ! bash -c "$cmd" >"$tmp/out.log" 2>&1; then
    echo "FAIL: $cmd"; tail -5 "$tmp/out.log"; fails=$((fails+1))
  fi
done <<< "$block"
[ -s "$tmp/tut/ltc_beckmann.glsl" ] || { echo "FAIL: no shader snippet"; fails=$((fails+1)); }
grep -q "ltc_beckmann_coord0" "$tmp/tut/ltc_beckmann.glsl" || { echo "FAIL: README names a shader function the snippet lacks"; fails=$((fails+1)); }
echo "test_readme_tutorial: $((n+2-fails)) passed, $fails failed"
[ $fails -eq 0 ]
