#!/usr/bin/env bash
# Replaces the vendored three.js with build/three.module.min.js and LICENSE of npm's `three@VERSION`.
set -euo pipefail
version="${1:?usage: refresh.sh VERSION (e.g. 0.170.0)}"
here="$(cd "$(dirname "$0")" && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack "three@$version" >/dev/null && tar xzf "three-$version.tgz" package/build/three.module.min.js package/LICENSE)
if grep -q "from['\"]\|import['\"]" "$tmp/package/build/three.module.min.js"; then
    echo "three@$version: build/three.module.min.js imports other files; the viewer inlines one file only" >&2
    exit 1
fi
cp "$tmp/package/build/three.module.min.js" "$tmp/package/LICENSE" "$here/"
sed -i "s/version\\s*\\*\\*[0-9.]*\\*\\*/version **$version**/" "$here/README.md"
echo "vendored three@$version"
