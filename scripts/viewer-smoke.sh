#!/usr/bin/env bash
# Viewer smoke test: opens `treelet view` on a real window (under Xvfb when no display is set),
# renders a few frames of `cornell`, writes a screenshot of the whole window and checks that the PNG
# exists and is not one flat colour. Prints 'viewer smoke: skipped (reason)' and exits 0 when no X
# server can be had. Builds the release binary first (a no-op when it is up to date).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -f "$HOME/.cargo/env" ]; then . "$HOME/.cargo/env"; fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/treelet-xdg-$(id -u)}"
mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"

skip() {
  echo "viewer smoke: skipped ($1)"
  exit 0
}

out_dir=$(mktemp -d)
xvfb_pid=""
cleanup() {
  if [ -n "$xvfb_pid" ]; then kill "$xvfb_pid" 2>/dev/null || true; fi
  rm -rf "$out_dir"
}
trap cleanup EXIT

if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
  command -v Xvfb >/dev/null 2>&1 || skip "no display and no Xvfb"
  # The first free display number from :99 up.
  display_num=99
  while [ -e "/tmp/.X11-unix/X$display_num" ] || [ -e "/tmp/.X$display_num-lock" ]; do
    display_num=$((display_num + 1))
  done
  Xvfb ":$display_num" -screen 0 1280x800x24 -nolisten tcp >"$out_dir/xvfb.log" 2>&1 &
  xvfb_pid=$!
  for _ in $(seq 1 50); do
    [ -e "/tmp/.X11-unix/X$display_num" ] && break
    kill -0 "$xvfb_pid" 2>/dev/null || break
    sleep 0.1
  done
  [ -e "/tmp/.X11-unix/X$display_num" ] || skip "Xvfb did not start: $(tail -n 1 "$out_dir/xvfb.log")"
  export DISPLAY=":$display_num"
fi
if [ -n "${DISPLAY:-}" ] && ! ldconfig -p 2>/dev/null | grep -q "libxkbcommon-x11.so"; then
  skip "libxkbcommon-x11 is not installed (the X11 keyboard library winit loads)"
fi

cargo build --release --quiet
shot="$out_dir/viewer.png"
./target/release/treelet view --scene cornell --width 1280 --height 800 \
  --screenshot "$shot" --exit-after-frames 8
[ -s "$shot" ] || { echo "viewer smoke: FAILED (no screenshot written)"; exit 1; }

# Decode the PNG (8-bit RGB/RGBA, non-interlaced, as the viewer writes it) and count colours.
python3 - "$shot" <<'PY'
import struct, sys, zlib

data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
pos, idat, header = 8, b"", None
while pos < len(data):
    (length,) = struct.unpack(">I", data[pos:pos + 4])
    kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
    if kind == b"IHDR":
        header = struct.unpack(">IIBBBBB", body)
    elif kind == b"IDAT":
        idat += body
    pos += 12 + length
width, height, depth, color, _, _, interlace = header
assert depth == 8 and color in (2, 6) and interlace == 0, f"unexpected PNG format {header}"
bpp = 3 if color == 2 else 4
raw, stride = zlib.decompress(idat), width * bpp
prev, colours = bytearray(stride), set()
for y in range(height):
    kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for i in range(stride):
        a = line[i - bpp] if i >= bpp else 0
        b, c = prev[i], prev[i - bpp] if i >= bpp else 0
        if kind == 1:
            line[i] = (line[i] + a) & 255
        elif kind == 2:
            line[i] = (line[i] + b) & 255
        elif kind == 3:
            line[i] = (line[i] + (a + b) // 2) & 255
        elif kind == 4:
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    if y % 4 == 0:
        colours.update(bytes(line[x:x + 3]) for x in range(0, stride, bpp * 4))
    prev = line
print(f"viewer smoke: screenshot {width}x{height}, {len(colours)} distinct colours (sampled)")
if len(colours) < 16:
    sys.exit("viewer smoke: FAILED (the screenshot is (nearly) one flat colour)")
PY
echo "viewer smoke: passed"
