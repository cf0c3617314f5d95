#!/usr/bin/env bash
# probes.sh [DATA]: the tool on the resource probes that can cost time or memory (huge claims,
# tiny resolutions, far rays, big k, oversized headers, many threads), each timed with its peak
# resident memory, under the default memory limit and under --memory-limit 1G where the command
# takes it. One row per run: probe, limit, exit status, seconds, peak MB, whether it stayed
# within 5 s and 1 GB, and the first line it printed on stderr. Run from the repository root
# after building (build/bin/knnocc, build/data/scan.dat). DATA: ../shared/data by default; the
# probes on the TUM clouds are left out without it. Needs /usr/bin/time (Debian package time)
# and python3. Takes about five minutes: some probes are legitimate work that runs long.
set -uo pipefail
K=$PWD/build/bin/knnocc
SCAN=$PWD/build/data/scan.dat
DATA=$(cd "${1:-../shared/data}" 2>/dev/null && pwd || true)
[ -x "$K" ] || { echo "probes.sh: build the tool first (build/bin/knnocc)"; exit 2; }
[ -x /usr/bin/time ] || { echo "probes.sh: needs /usr/bin/time (apt-get install time)"; exit 2; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W" || exit 2

# Inputs, all generated.
python3 - <<'PY'
import random, struct
random.seed(4)
# 20,000 points spread over +-4 km, seen from the origin.
with open("far.xyz", "w") as f:
    for _ in range(20000):
        f.write("%f %f %f\n" % tuple(random.uniform(-4000, 4000) for _ in range(3)))
# A 24 MB binary_compressed PCD that claims (and holds) 178 M points, 2.1 GB once decoded, and
# the same file with one reference turned into a literal run: the stream no longer adds up.
n = 178_000_000; raw = n * 12
body = bytearray(b"\x00\x00")
full = (raw - 1) // 264
body += bytes([0xE0, 255, 0]) * full
rest = raw - 1 - full * 264
while rest > 0:
    k = min(32, rest); body += bytes([k - 1]) + b"\x00" * k; rest -= k
head = ("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH %d\nHEIGHT 1\n"
        "POINTS %d\nDATA binary_compressed\n" % (n, n)).encode()
open("claims_2gb.pcd", "wb").write(head + struct.pack("<II", len(body), raw) + bytes(body))
body[2 + 3 * (len(body) // 6)] = 0x1F
open("claims_2gb_broken.pcd", "wb").write(head + struct.pack("<II", len(body), raw) + bytes(body))
# Two free leaves at depth 6: a 71-byte .bt that expands to 2^31 voxels.
open("giant.bt", "wb").write(b"# Octomap OcTree binary file\nid OcTree\nsize 8\nres 0.1\ndata\n"
                              + b"\x03\x00" * 5 + b"\x05\x00")
# Headers: 200,000 PLY properties, 200,000 PCD fields, 80,000 PLY elements.
props = "".join("property float f%d\n" % i for i in range(200000))
open("props.ply", "w").write("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                             "property float y\nproperty float z\n" + props + "end_header\n")
open("fields.pcd", "w").write("VERSION 0.7\nFIELDS x y z" + "".join(" f%d" % i for i in range(200000))
                              + "\nSIZE 4 4 4\n")
elems = "".join("element e%d 0\nproperty float v\n" % i for i in range(80000))
open("elements.ply", "w").write("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                "property float y\nproperty float z\n" + elems + "end_header\n0 0 1\n")
PY
printf '1 0 0\n0 2 0\n0 0 1.5\n' > p.xyz

printf '%-26s %-8s %4s %8s %8s %-6s %s\n' probe limit exit seconds peak_MB 5s/1GB "first line on stderr"
# probe NAME LIMIT TIMEOUT cmd...: LIMIT "-" runs cmd as given, else adds --memory-limit LIMIT.
probe() {
  local name=$1 limit=$2 secs=$3; shift 3
  local args=("$@")
  [ "$limit" = - ] || args+=(--memory-limit "$limit")
  /usr/bin/time -f "%e %M" -o time.txt timeout "$secs" "${args[@]}" > /dev/null 2> err.txt
  local rc=$?
  read -r s kb < <(tail -n 1 time.txt)
  local mb=$((kb / 1024)) ok=yes
  if [ "$rc" = 124 ]; then ok="no"; s=">$secs"; fi
  if [ "$ok" = yes ]; then
    awk -v s="$s" -v mb="$mb" 'BEGIN { exit !(s <= 5 && mb <= 1024) }' || ok=no
  fi
  printf '%-26s %-8s %4s %8s %8s %-6s %s\n' "$name" "${limit/-/default}" "$rc" "$s" "$mb" "$ok" \
    "$(head -n 1 err.txt | cut -c 1-110)"
}

for lim in - 1G; do
  [ -n "$DATA" ] && probe tum_res_0.0001 "$lim" 300 "$K" map --input "$DATA/tum_fr2_pioneer_slam2" --res 0.0001
  probe scan.dat_res_0.001 "$lim" 300 "$K" map --input "$SCAN" --res 0.001
  probe far_rays_4km_res_1 "$lim" 300 "$K" map --input far.xyz --res 1
  probe pcd_claims_2gb_broken "$lim" 300 "$K" map --input claims_2gb_broken.pcd --res 0.1
  probe scan.dat_knn_k4096 "$lim" 60 "$K" map --input "$SCAN" --model knn --k 4096 --res 0.1
  probe threads_512 "$lim" 60 "$K" map --input p.xyz --res 0.1 --threads 512
  probe ply_200k_properties "$lim" 60 "$K" map --input props.ply --res 0.1
  probe pcd_200k_fields "$lim" 60 "$K" map --input fields.pcd --res 0.1
  probe ply_80k_elements "$lim" 60 "$K" map --input elements.ply --res 0.1
done
probe pcd_claims_2gb_valid - 300 "$K" info claims_2gb.pcd
probe pcd_claims_2gb_broken - 300 "$K" info claims_2gb_broken.pcd
probe bt_2^31_voxels - 60 "$K" convert giant.bt giant_out.bt
