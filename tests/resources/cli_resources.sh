#!/usr/bin/env bash
# Resource, output and bad-data probes of the knnocc tool, one case per ctest test:
#   cli_resources.sh TOOL WORK_DIR CASE
# Each case builds its inputs, runs the tool as a user would and checks the exit status, the
# one-line message and which files exist afterwards. Exit 0 = pass.
set -u
K=$1
W=$2/$3
CASE=$3
rm -rf "$W" && mkdir -p "$W" && cd "$W" || exit 1
printf '1 0 0\n0 2 0\n0 0 1.5\n' > p.xyz

fail() { echo "FAIL: $*"; exit 1; }
# expect RC REGEX cmd...: runs cmd, stderr must match REGEX (one line) and the status be RC.
expect() {
  local rc=$1 re=$2; shift 2
  "$@" > out.txt 2> err.txt
  local got=$?
  echo "\$ $* -> $got"; cat err.txt
  [ "$got" = "$rc" ] || fail "exit $got, expected $rc"
  if [ -n "$re" ]; then grep -Eq -- "$re" err.txt || fail "stderr does not match: $re"; fi
  [ "$rc" = 0 ] || [ "$(wc -l < err.txt)" -le 1 ] || fail "more than one line on stderr"
}
no_temporaries() { ! ls -a | grep -q '\.tmp-' || fail "temporary left behind: $(ls -a | grep '\.tmp-')"; }

# killed_mid_run SIG RC: a long `sim --out big` gets SIG once its staging folder exists; it must
# die of the signal (exit RC) leaving neither big/ nor any temporary.
killed_mid_run() {
  "$K" sim --out big --keyframes 100000 > /dev/null 2>&1 &
  local pid=$! rc
  for i in $(seq 50); do ls -a | grep -q 'big\.tmp-' && break; sleep 0.1; done
  ls -a | grep -q 'big\.tmp-' || fail "no staging folder seen"
  sleep 0.5
  kill -"$1" $pid; wait $pid; rc=$?
  [ $rc = "$2" ] || fail "exit $rc after SIG$1, expected $2 (killed by the signal)"
  [ ! -e big ] || fail "big/ exists after SIG$1"
  no_temporaries
}

# zeros_pcd [broken]: zeros.pcd, a 4 MB compressed PCD of 33 M points that expands to 400 MB;
# "broken" turns one reference in the middle into a literal run, so the stream no longer adds up.
zeros_pcd() {
  python3 - "${1:-}" <<'PY' || { echo "SKIPPED: no python3"; exit 0; }
import struct, sys
n = 33_333_333; raw = n * 12
body = bytearray(b"\x00\x00")  # one literal zero byte
left = raw - 1
while left >= 3:
    ln = min(left, 264)
    body += bytes([0xE0, ln - 9, 0x00]) if ln >= 9 else bytes([(ln - 2) << 5, 0x00])
    left -= ln
assert left == 0 or left < 3
if left:
    body += bytes([left - 1]) + b"\x00" * left
if sys.argv[1] == "broken":
    body[2 + 3 * (len(body) // 6)] = 0x1F
head = ("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH %d\nHEIGHT 1\n"
        "POINTS %d\nDATA binary_compressed\n" % (n, n)).encode()
open("zeros.pcd", "wb").write(head + struct.pack("<II", len(body), raw) + bytes(body))
PY
}

case "$CASE" in
  missing_output_dir)  # fails before mapping: nothing written
    expect 2 "missing_dir/a.bt: folder 'missing_dir' does not exist" \
      "$K" map --input p.xyz --res 0.1 --out-voxels a.txt --out-bt missing_dir/a.bt
    [ ! -e a.txt ] || fail "a.txt written although another output cannot be"
    no_temporaries ;;
  same_output_twice)
    expect 2 "name the same file" "$K" map --input p.xyz --res 0.1 --out-voxels a.txt --out-ply ./a.txt
    expect 2 "name the same file" "$K" track --input . --k 3 --out-stats f --out-s f
    echo old > a.bt && ln -s a.bt link.bt
    expect 2 "name the same file" "$K" map --input p.xyz --res 0.1 --out-bt a.bt --out-ot x.ot --out-png y.png --out-voxels link.bt
    [ ! -e a.txt ] && [ ! -e f ] && [ "$(cat a.bt)" = old ] || fail "an output was written" ;;
  empty_output_name)
    expect 2 "--out-voxels needs a file name, got ''" "$K" map --input p.xyz --res 0.1 --out-voxels "" ;;
  output_is_folder)
    mkdir d
    expect 2 "d: is a folder" "$K" map --input p.xyz --res 0.1 --out-voxels d ;;
  device_written_in_place)  # /dev/null stays a device; a FIFO is written, not replaced
    expect 0 "" "$K" map --input p.xyz --res 0.1 --out-voxels /dev/null --out-ply /dev/null
    [ -c /dev/null ] || fail "/dev/null replaced"
    mkfifo fifo
    (wc -l < fifo > fifo_lines) &
    expect 0 "" "$K" map --input p.xyz --res 0.1 --out-voxels fifo
    wait
    [ -p fifo ] || fail "FIFO replaced by a regular file"
    [ "$(cat fifo_lines)" = 43 ] || fail "FIFO reader got $(cat fifo_lines) lines, expected 43"
    no_temporaries ;;
  user_tmp_untouched)  # a user's <target>.tmp is neither used nor removed
    echo mine > victim.txt.tmp
    expect 0 "" "$K" map --input p.xyz --res 0.1 --out-voxels victim.txt
    [ "$(cat victim.txt.tmp)" = mine ] || fail "victim.txt.tmp changed"
    [ "$(wc -l < victim.txt)" = 43 ] || fail "victim.txt incomplete"
    no_temporaries ;;
  concurrent_writers)  # two runs writing one path at once: a complete file, exit 0 both
    "$K" map --input p.xyz --res 0.02 --out-voxels ref.txt > /dev/null || fail "reference run"
    for i in 1 2 3 4; do "$K" map --input p.xyz --res 0.02 --out-voxels same.txt > /dev/null & done
    for j in 1 2 3 4; do wait -n || fail "a concurrent run failed"; done
    cmp -s ref.txt same.txt || fail "concurrent writers left a file unlike a single run's"
    no_temporaries ;;
  stdout_full)
    [ -w /dev/full ] || { echo "SKIPPED: no /dev/full"; exit 0; }
    "$K" map --input p.xyz --res 0.1 > /dev/full 2> err.txt; rc=$?; cat err.txt
    [ $rc = 2 ] || fail "exit $rc with stdout on /dev/full"
    grep -q "standard output: write failed" err.txt || fail "no message" ;;
  png_extension)
    expect 2 "--out-png .*ending in .png, got 'x.jpg'" "$K" map --input p.xyz --res 0.1 --out-png x.jpg ;;
  sim_non_empty_folder)
    mkdir old && touch old/keep
    expect 2 "old: folder is not empty" "$K" sim --out old --keyframes 2
    [ "$(ls old)" = keep ] || fail "old/ changed"
    expect 2 "folder is not empty" "$K" demo --seeds 1 --out old
    mkdir empty
    expect 0 "" "$K" sim --out empty --keyframes 2
    [ -f empty/poses.txt ] && [ -f empty/reference.txt ] || fail "sim did not fill the empty folder"
    no_temporaries ;;
  sigterm_removes_temporaries)  # SIGTERM mid-run: the staging folder is removed, no target made
    killed_mid_run TERM 143 ;;
  threads_capped)  # more threads than the machine has: capped with a note, the same map
    "$K" map --input p.xyz --res 0.1 > one.txt || fail "one thread"
    expect 0 "is more than the [0-9]+ hardware threads of this machine; using" \
      timeout 60 "$K" map --input p.xyz --res 0.1 --threads 512
    [ "$(cut -d' ' -f1-8 out.txt)" = "$(cut -d' ' -f1-8 one.txt)" ] || fail "a different map" ;;
  huge_ply_header)  # 200,000 properties (4.5 MB of header): refused at once
    { printf 'ply\nformat ascii 1.0\nelement vertex 1\n'; seq 200000 | sed 's/^/property uchar p/'
      printf 'end_header\n'; } > huge.ply
    expect 2 "huge.ply: PLY header is longer than 1 MiB" timeout 20 "$K" map --input huge.ply --res 0.1 ;;
  huge_pcd_header)
    { printf 'VERSION 0.7\nFIELDS x y z'; seq 200000 | sed 's/^/ f/' | tr -d '\n'; printf '\n'; } > huge.pcd
    expect 2 "huge.pcd: PCD header is longer than 1 MiB" timeout 20 "$K" map --input huge.pcd --res 0.1 ;;
  memory_far_rays)  # 20,000 rays to +-4 km at 1 m under a small limit: one line, nothing written
    awk 'BEGIN { srand(1); for (i = 0; i < 20000; i++) printf "%f %f %f\n", 8000*rand()-4000, 8000*rand()-4000, 8000*rand()-4000 }' > far.xyz
    expect 2 "far.xyz: its rays need more than [0-9]+ bricks .* --memory-limit 300 MB" \
      timeout 30 "$K" map --input far.xyz --res 1 --memory-limit 300M --out-voxels far.txt
    [ ! -e far.txt ] || fail "far.txt written"
    # Sanitizer builds set no address-space limit: the second half needs it.
    [ -z "${KNNOCC_TOOL_SANITIZED:-}" ] || exit 0
    # Past what the estimate can prove, the limit still holds: the map and the inserter's scratch
    # share it (MemoryLimitError, before the address-space limit is reached): one line naming
    # file and limit.
    expect 2 "far.xyz: the map needs more memory at --res 1: .*--memory-limit 1.0 GB" \
      timeout 60 "$K" map --input far.xyz --res 1 --memory-limit 1G --out-voxels far.txt
    [ ! -e far.txt ] || fail "far.txt written"
    # 1,000 of those rays fit the default limit (about 0.4 GB: bricks crossed once stay uniform).
    head -1000 far.xyz > far1k.xyz
    expect 0 "" timeout 60 "$K" map --input far1k.xyz --res 1 --out-bt far1k.bt
    [ -s far1k.bt ] || fail "far1k.bt not written"
    no_temporaries ;;
  memory_tiny_resolution)  # a dense 2 m scan at 0.1 mm
    awk 'BEGIN { srand(2); for (i = 0; i < 50000; i++) printf "%f %f %f\n", 3*rand()-1.5, 3*rand()-1.5, 1.5 }' > room.xyz
    expect 2 "room.xyz: .*--memory-limit 500 MB" timeout 30 "$K" map --input room.xyz --res 0.0001 --memory-limit 500M ;;
  memory_long_fine_rays)  # 20,000 rays of 3 m at 0.1 mm: refused from their directions, before mapping
    awk 'BEGIN { srand(3); for (i = 0; i < 20000; i++) { z = 2*rand()-1; a = 6.2831853*rand(); r = sqrt(1-z*z);
                 printf "%f %f %f\n", 3*r*cos(a), 3*r*sin(a), 3*z } }' > sphere.xyz
    expect 2 "sphere.xyz: its rays need more than [0-9]+ bricks .*--memory-limit 1.0 GB" \
      timeout 30 "$K" map --input sphere.xyz --res 0.0001 --memory-limit 1G ;;
  memory_out_of_memory)  # a 4 MB compressed PCD that expands to 400 MB, under a 200 MB limit
    [ -z "${KNNOCC_TOOL_SANITIZED:-}" ] || { echo "SKIPPED: sanitizer build, no address-space limit"; exit 0; }
    zeros_pcd
    expect 2 "zeros.pcd: out of memory \(--memory-limit 200 MB\)" timeout 30 "$K" map --input zeros.pcd --res 0.1 --memory-limit 200M ;;
  memory_broken_compressed)  # the same file, broken: the stream is checked before allocating
    zeros_pcd broken
    expect 2 "zeros.pcd: corrupt binary_compressed data: LZF data decodes to [0-9]+ bytes, not the declared 399999996" \
      timeout 30 "$K" map --input zeros.pcd --res 0.1 --memory-limit 200M ;;
  memory_corrections)  # the live mapper of --corrections holds the limit too
    "$K" sim --out seq --seed 3 --keyframes 12 --drift 0.3 > /dev/null || fail "sim"
    expect 2 "seq: keyframe [0-9]+: out of memory \(--memory-limit 64 MB\) mapping or correcting at --res 0.002" \
      timeout 30 "$K" map --input seq --corrections seq/corrections --res 0.002 --memory-limit 64M --out-voxels c.txt
    [ ! -e c.txt ] || fail "c.txt written"
    no_temporaries ;;
  bad_memory_limit)
    expect 2 "--memory-limit expects a size from 16M to 1000000T such as 800M or 4G, got '5'" \
      "$K" map --input p.xyz --res 0.1 --memory-limit 5 ;;
  missing_input)
    expect 2 "/nonexistent: cannot open: No such file or directory" "$K" map --input /nonexistent --res 0.1 ;;
  velodyne_without_calib)
    mkdir -p kitti/velodyne && printf '1 0 0 0 0 1 0 0 0 0 1 0\n' > kitti/poses.txt
    printf '\0\0\x80\x3f\0\0\0\0\0\0\0\0\0\0\0\0' > kitti/velodyne/000000.bin
    expect 2 "kitti/calib.txt: missing: a velodyne/ sequence needs KITTI's calib.txt" \
      "$K" map --input kitti --res 0.1 ;;
  utf8_bom_accepted)
    printf '\xef\xbb\xbf1 0 0\n0 2 0\n0 0 1.5\n' > bom.xyz
    expect 0 "" "$K" map --input bom.xyz --res 0.1
    grep -q "^clouds 1 points 3 " out.txt || fail "BOM file not read as 3 points" ;;
  mixed_ids_name_the_file)
    mkdir -p seq/clouds && printf '0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n' > seq/poses.txt
    printf 'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty uint id\nend_header\n1 0 0 7\n' > seq/clouds/000000.ply
    printf 'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 0 0\n' > seq/clouds/000001.ply
    expect 2 "seq/clouds/000001.ply: .*with and without ids" "$K" map --input seq --res 0.1 --model knn ;;
  info_like_map)  # info refuses what map refuses: a 1e-9 m tree, a non-unit VIEWPOINT
    printf '# Octomap OcTree binary file\nid OcTree\nsize 1\nres 1e-9\ndata\n\x00\x00' > tiny.bt
    expect 2 "tiny.bt: (header line 4: )?resolution 1e-09 is below" "$K" info tiny.bt
    expect 2 "tiny.bt: (header line 4: )?resolution 1e-09 is below" "$K" convert tiny.bt copy.bt
    printf 'FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 2 0 0 0\nDATA ascii\n1 0 0\n' > vp.pcd
    expect 2 "vp.pcd: VIEWPOINT quaternion norm 2.000000 is not 1" "$K" map --input vp.pcd --res 0.1
    expect 2 "vp.pcd: VIEWPOINT quaternion norm 2.000000 is not 1" "$K" info vp.pcd ;;
  memory_big_tree)  # a .bt whose one leaf covers 2^30 voxels: every command that loads a map
    # refuses it under a small limit, naming the file and --memory-limit (root and 4 inner nodes
    # with child 0 inner, the depth-5 node with child 0 an occupied leaf at depth 6)
    printf '# Octomap OcTree binary file\nid OcTree\nsize 7\nres 0.1\ndata\n\x03\x00\x03\x00\x03\x00\x03\x00\x03\x00\x02\x00' > big.bt
    msg="big.bt: the tree's 1073741824 voxels need at least .* more than the map's share .* of --memory-limit 100 MB"
    expect 2 "$msg" "$K" convert big.bt out.ot --memory-limit 100M
    expect 2 "$msg" "$K" view big.bt -o page.html --memory-limit 100M
    printf 'ground 0\nellipsoid 0 0 1 1 1 1\n' > ref.txt
    expect 2 "$msg" "$K" eval --map big.bt --reference ref.txt --memory-limit 100M
    expect 2 "$msg" "$K" map --input p.xyz --init-map big.bt --memory-limit 100M --out-ot x.ot
    [ ! -e out.ot ] && [ ! -e page.html ] && [ ! -e x.ot ] || fail "an output was written"
    no_temporaries ;;
  output_is_input)  # an output that is an input, or lies in an input folder: one line, nothing written
    "$K" sim --out seq --seed 3 --keyframes 12 --drift 0.3 > /dev/null || fail "sim"
    "$K" map --input p.xyz --res 0.1 --out-bt small.bt --out-ply a.ply > /dev/null || fail "map"
    ln -s small.bt link.bt && ln small.bt hard.bt && ln -s seq seqlink && mkdir corr lseq
    cp seq/corrections/* corr/ && cp -r seq/poses.txt lseq/ && mkdir lseq/clouds
    for f in seq/clouds/*; do ln -s "$PWD/$f" lseq/clouds/; done  # clouds linked in from seq
    inputs() { find seq corr lseq small.bt a.ply p.xyz -exec md5sum {} + 2> /dev/null | sort; }
    before=$(inputs)
    expect 2 "^knnocc view: small.bt: --out would replace an input \('small.bt' of MAP\); nothing was written$" \
      "$K" view small.bt -o small.bt
    expect 2 "link.bt: --out would replace an input \('small.bt' of MAP\)" "$K" view small.bt -o link.bt
    expect 2 "hard.bt: OUT would replace an input \('small.bt' of IN\)" "$K" convert small.bt hard.bt
    expect 2 "a.ply: --out-ply would replace an input \('a.ply' of --input\)" \
      "$K" map --input a.ply --res 0.1 --out-ply a.ply
    expect 2 "seq/poses.txt: --out-voxels would replace an input \('seq/poses.txt' of --input\)" \
      "$K" map --input seq --res 0.1 --out-voxels seq/poses.txt
    expect 2 "seq/map.bt: --out-bt lies inside an input folder \('seq' of --input\)" \
      "$K" map --input seq --res 0.1 --out-voxels v.txt --out-bt seq/map.bt
    expect 2 "seqlink/clouds/new.ply: --out-ply lies inside an input folder \('seq/clouds' of --input\)" \
      "$K" map --input seq --res 0.1 --out-ply seqlink/clouds/new.ply
    expect 2 "seq/clouds/000003.ply: --out-ply would replace an input \('lseq/clouds/000003.ply' of --input\)" \
      "$K" map --input lseq --res 0.1 --out-ply seq/clouds/000003.ply
    expect 2 "seq/corrections/after_000009.txt: --out-voxels would replace an input" \
      "$K" map --input seq --corrections seq/corrections --res 0.1 --out-voxels seq/corrections/after_000009.txt
    expect 2 "corr/new.txt: --out-voxels lies inside an input folder \('corr' of --corrections\)" \
      "$K" map --input seq --corrections corr --res 0.1 --out-voxels corr/new.txt
    expect 2 "small.bt: --out-bt would replace an input \('small.bt' of --init-map\)" \
      "$K" map --input p.xyz --init-map small.bt --out-bt small.bt
    expect 2 "seq/clouds/000001.ply: --out-stats would replace an input \('seq/clouds/000001.ply' of --input\)" \
      "$K" track --input seq --k 3 --out-stats seq/clouds/000001.ply
    expect 2 "seq/s.txt: --out-s lies inside an input folder" "$K" track --input seq --k 3 --out-stats s.txt --out-s seq/s.txt
    [ "$(inputs)" = "$before" ] || fail "an input changed"
    for f in v.txt seq/map.bt seq/clouds/new.ply corr/new.txt s.txt seq/s.txt; do
      [ ! -e "$f" ] || fail "$f written"
    done
    [ -z "$(find . -name '*.tmp-*')" ] || fail "temporaries left: $(find . -name '*.tmp-*')"
    expect 0 "" "$K" map --input seq --res 0.1 --out-bt seq.bt  # beside the folder: written
    [ -s seq.bt ] || fail "seq.bt not written" ;;
  control_bytes_escaped)  # bytes of a file reach the terminal escaped, a NUL does not cut the line
    printf '# Octomap OcTree binary file\nid Oc\033[2JTree\000X\nsize 0\nres 0.1\ndata\n' > esc.bt
    expect 2 "esc.bt: unsupported OctoMap tree type 'Oc\\\\x1b\[2JTree\\\\x00X' \(supported" "$K" info esc.bt
    ! grep -q $'\033' err.txt || fail "a raw ESC byte on stderr"
    printf 'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\033]0;t\007\nproperty float x\033]0;t\007\nend_header\n' > esc.ply
    expect 2 "esc.ply: PLY header line 5: duplicate property 'x\\\\x1b\]0;t\\\\x07' in element 'vertex'" \
      "$K" map --input esc.ply --res 0.1
    "$K" sim --out seq --seed 3 --keyframes 4 > /dev/null || fail "sim"
    mkdir corr && printf '0 0 0 0 0 0 0 1\033[1m\n' > corr/after_000000.txt
    expect 2 "corr/after_000000.txt: line 1: cannot parse '1\\\\x1b\[1m' as a number" \
      "$K" map --input seq --corrections corr --res 0.1
    ! grep -q $'\033' err.txt || fail "a raw ESC byte on stderr"
    # File names a command prints (wrote lines, notes) are escaped too.
    printf 'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n1 0 0 9 9 9\n' > $'c\033[1m.ply'
    "$K" convert $'c\033[1m.ply' $'o\001.xyz' > out.txt 2> err.txt || fail "convert"
    grep -q 'wrote o\\x01.xyz' out.txt || fail "the wrote line does not escape the name: $(cat -v out.txt)"
    grep -q 'c\\x1b\[1m.ply: note' err.txt || fail "the note does not escape the name: $(cat -v err.txt)"
    ! grep -q $'[\001\033]' out.txt err.txt || fail "a raw control byte reached the terminal" ;;
  corrections_checked)  # snapshots must fit the keyframes: names, duplicates, stamps, rows
    "$K" sim --out seq --seed 3 --keyframes 12 --drift 0.3 > /dev/null || fail "sim"
    snap() { rm -rf c && mkdir c && cp seq/corrections/* c/; }
    snap && cp c/after_000009.txt c/after_9.txt
    expect 2 "c/after_9.txt: a second snapshot of keyframe 9 \(also after_000009.txt\)" \
      "$K" map --input seq --corrections c --res 0.1 --out-voxels v.txt
    for name in AFTER_000009.txt after_000009.TXT after_abc.txt after9.txt; do
      snap && mv c/after_000009.txt "c/$name"
      expect 2 "c/$name: not a snapshot name: snapshots are after_N.txt" \
        "$K" map --input seq --corrections c --res 0.1 --out-voxels v.txt
    done
    snap && grep -v '^#' seq/corrections/after_000009.txt | tac > c/after_000009.txt  # rows reversed
    expect 2 "c/after_000009.txt: line 1: stamp 9.000000 is not keyframe 0's \(0.000000 in poses.txt; tolerance 1e-4 s\)" \
      "$K" map --input seq --corrections c --res 0.1 --out-voxels v.txt
    snap && awk '!/^#/ { $1 = $1 + 1 } 1' seq/corrections/after_000009.txt > c/after_000009.txt  # shifted
    expect 2 "c/after_000009.txt: line 2: stamp 1.000000 is not keyframe 0's" \
      "$K" map --input seq --corrections c --res 0.1 --out-voxels v.txt
    # 600 MB that should hold 10 rows: refused at row 11, the file never read whole.
    snap && echo '10 0 0 0 0 0 0 1' >> c/after_000009.txt && truncate -s 600M c/after_000009.txt
    expect 2 "c/after_000009.txt: line 12: more poses than the 10 expected" \
      timeout 5 "$K" map --input seq --corrections c --res 0.1 --memory-limit 1G --out-voxels v.txt
    [ ! -e v.txt ] || fail "v.txt written"
    snap && expect 0 "" "$K" map --input seq --corrections c --res 0.1 --out-voxels v.txt
    [ -s v.txt ] || fail "the good snapshots were refused" ;;
  corrections_velodyne_frame)  # KITTI: snapshot rows are poses.txt's rows, calib.txt's Tr applied alike
    mkdir -p kitti/velodyne kitti/c
    printf 'Tr: 0 -1 0 0.1 0 0 -1 -0.2 1 0 0 0.3\n' > kitti/calib.txt
    printf '1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0.5\n' > kitti/poses.txt
    for i in 0 1; do  # two points, 3 m and 4 m ahead of the Velodyne
      printf '\0\0\x40\x40\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x80\x40\0\0\x80\x3f\0\0\0\0\0\0\0\0' > kitti/velodyne/00000$i.bin
    done
    cp kitti/poses.txt kitti/c/after_000001.txt  # the same poses: nothing to correct
    "$K" map --input kitti --res 0.1 --out-voxels plain.txt > /dev/null || fail "plain map"
    expect 0 "" "$K" map --input kitti --corrections kitti/c --res 0.1 --out-voxels live.txt
    grep -q "^corrections 1 reposed_keyframes 0 " out.txt || fail "keyframes re-posed: $(cat out.txt)"
    cmp -s plain.txt live.txt || fail "the corrected map differs from the plain one" ;;
  corrections_key_range_note)  # a correction that moves points out of the key range: map's note
    "$K" sim --out seq --seed 3 --keyframes 12 --drift 0.3 > /dev/null || fail "sim"
    mkdir c && awk '!/^#/ && ++n == 4 { $2 = $2 + 5000 } 1' seq/corrections/after_000009.txt > c/after_000009.txt
    "$K" map --input seq --corrections c --res 0.1 > out.txt 2> err.txt || fail "exit $?"
    cat err.txt
    grep -Eq "^knnocc map: seq: skipped [1-9][0-9]* points outside the map's key range \(\|c\| >= 3276.8 m at --res 0.1\)" err.txt ||
      fail "no key-range note"
    n=$(grep -o 'skipped [0-9]*' err.txt | cut -d' ' -f2)
    # the same count as plain map with that keyframe's pose
    mkdir -p moved && cp -r seq/clouds moved/ && { head -1 seq/poses.txt; sed -n 2,11p seq/corrections/after_000009.txt | awk 'NR == 4 { $2 = $2 + 5000 } 1'; sed -n 12,13p seq/poses.txt; } > moved/poses.txt
    "$K" map --input moved --res 0.1 > /dev/null 2> err2.txt || fail "plain map"
    cat err2.txt
    grep -q "skipped $n points outside the map's key range" err2.txt || fail "plain map skips another count" ;;
  unmappable_values)  # refused on read, or a warning: never a map of nonsense without a word
    "$K" map --input p.xyz --res 0.1 --out-bt small.bt > /dev/null || fail "map"
    sed 's/^res 0.1$/res 1e308/' small.bt > huge.bt
    expect 2 "huge.bt: header line [0-9]+: resolution 1e\+308 is above 1.03846e\+34 m: the key range" "$K" view huge.bt -o h.html
    expect 2 "huge.bt: header line [0-9]+: resolution 1e\+308 is above" "$K" convert huge.bt h.ply
    [ ! -e h.html ] && [ ! -e h.ply ] || fail "an output of the 1e308 map was written"
    expect 2 "small.bt: resolution 0.1 differs from --res 0.1000001" \
      "$K" map --input p.xyz --res 0.1000001 --init-map small.bt --out-bt q.bt
    mkdir -p rep/clouds && printf '0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n' > rep/poses.txt
    for i in 0 1; do printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uint id\nend_header\n1 0 0 7\n1 0.5 0 7\n1 1 0 8\n' > rep/clouds/00000$i.ply; done
    for model in robust knn; do
      expect 2 "rep/clouds/000000.ply: insert_keyframe: map-point id 7 appears twice in one keyframe" \
        "$K" map --input rep --res 0.1 --model $model
    done
    expect 2 "rep/clouds/000000.ply: KeyframeUnion: map-point id 7 appears twice" "$K" track --input rep --k 1 --out-stats st.txt
    mkdir rep/c && expect 2 "rep/clouds/000000.ply: LiveMapper::add: map-point id 7 appears twice" \
      "$K" map --input rep --model knn --corrections rep/c --res 0.1
    # an empty map from clouds that hold points: a warning, exit 0 (a cloud whose own coordinates
    # all lie beyond the key range is an error instead, naming the likely cause: map_run.hpp)
    printf 'nan 0 0\n' > far.xyz
    "$K" map --input far.xyz --res 0.1 > out.txt 2> err.txt || fail "exit $?"
    grep -q "far.xyz: warning: the map is empty: the 1 points of 1 clouds updated no voxel" err.txt || fail "no warning"
    "$K" sim --out seq1 --seed 3 --keyframes 1 > /dev/null || fail "sim"
    "$K" map --input seq1 --res 0.1 --model robust > out.txt 2> err.txt || fail "exit $?"
    grep -q "seq1: warning: the map is empty: .* the robust model adds a map point's evidence only while it believes" err.txt ||
      fail "no warning for the robust model"
    # eval without --against: n/a, not 0, and it says why
    "$K" eval --ids seq1 --map small.bt > out.txt 2> err.txt || fail "eval"
    grep -q "reference_kept n/a lost n/a" out.txt && grep -q "reference_kept and lost need --against" err.txt ||
      fail "eval: $(cat out.txt err.txt)"
    expect 2 "--keyframes 100000 with --drift would write about 76.2 GB, more than the 1.0 GB sim writes" \
      timeout 5 "$K" sim --out big --keyframes 100000 --drift 0.1
    [ ! -e big ] || fail "big/ written"
    expect 2 "at most 64 maps fit one page; 'small.bt' is one too many" "$K" view $(for i in $(seq 65); do echo small.bt; done) -o v.html ;;
  save_every_resumes)  # snapshots say which clouds they hold; resumed, the one run's map
    "$K" sim --out seq --seed 3 --keyframes 12 > /dev/null || fail "sim"
    expect 0 "" "$K" map --input seq --res 0.1 --count 7 --save-every 3 --out-bt part.bt --out-ot part.ot
    for f in part.bt part.ot; do
      "$K" info $f | grep -q "^note: map: clouds 0 to 6 of seq; continue with --first 7$" || fail "$f: no note"
    done
    expect 2 "--init-map part.ot holds clouds 0 to 6 of seq: continue with --first 7, not 5" \
      "$K" map --input seq --init-map part.ot --first 5 --out-ot whole.ot
    expect 0 "" "$K" map --input seq --init-map part.ot --first 7 --out-ot whole.ot --save-every 2
    "$K" info whole.ot | grep -q "^note: map: clouds 0 to 11 of seq; continue with --first 12$" || fail "no note"
    expect 0 "" "$K" map --input seq --res 0.1 --out-ot one.ot
    "$K" convert whole.ot plain.ot > /dev/null && cmp plain.ot one.ot || fail "the resumed map is not the one run's" ;;
  stale_temporaries_removed)  # a killed run's temporary goes at the next start; a live writer's stays
    printf 'partial' > a.bt.tmp-Ab12Cd && touch -d '1 minute ago' a.bt.tmp-Ab12Cd
    printf 'partial' > a.bt.tmp-Ef34Gh && touch -d '1 minute ago' a.bt.tmp-Ef34Gh
    exec 9< a.bt.tmp-Ef34Gh && flock -n 9 || fail "flock"  # as a writer at work holds its temporary
    mkfifo a.bt.tmp-Ff1f0X  # a FIFO of that name is not opened (it would wait for a writer)
    expect 0 "" timeout 20 "$K" map --input p.xyz --res 0.1 --out-bt a.bt
    [ -p a.bt.tmp-Ff1f0X ] || fail "the FIFO was removed"
    rm a.bt.tmp-Ff1f0X
    [ ! -e a.bt.tmp-Ab12Cd ] || fail "the stale temporary is still there"
    [ -e a.bt.tmp-Ef34Gh ] || fail "a locked temporary was removed"
    exec 9<&-  # the writer is gone: its temporary is stale
    expect 0 "" "$K" map --input p.xyz --res 0.1 --out-bt a.bt
    no_temporaries ;;
  corrections_outputs_all_or_none)  # --corrections writes its outputs as one set, like plain map
    "$K" sim --out s1 --seed 3 --keyframes 12 --drift 0.3 > /dev/null || fail "sim"
    # --crop 0.001 leaves an empty map, which the page refuses after the other files are written
    expect 2 "p.html: .*no occupied voxel" "$K" map --input s1 --res 0.1 --corrections s1/corrections --crop 0.001 \
      --out-voxels v.txt --out-bt m.bt --out-html p.html
    [ ! -e v.txt ] && [ ! -e m.bt ] && [ ! -e p.html ] || fail "part of the outputs was written"
    no_temporaries ;;
  dangling_link_keeps_user_files)  # an output that is a dangling link: no stray file removed
    printf 'mine' > .tmp-abcdef && touch -d '1 minute ago' .tmp-abcdef
    ln -s missing/target out.xyz
    "$K" convert p.xyz out.xyz > /dev/null 2>&1
    [ "$(cat .tmp-abcdef)" = mine ] || fail "a user's .tmp-abcdef was removed" ;;
  heldout_repeated_id)  # a map-point id twice in one keyframe: the cloud named, before any model
    mkdir -p seq/clouds && printf '0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n' > seq/poses.txt
    printf 'ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty uint id\nend_header\n1 0 0 7\n1 1 0 8\n' > seq/clouds/000000.ply
    printf 'ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty uint id\nend_header\n1 0 0 5\n1 1 0 5\n' > seq/clouds/000001.ply
    expect 2 "seq/clouds/000001.ply: .*map-point id 5 appears twice" "$K" eval --heldout seq --folds 2
    [ ! -s out.txt ] || fail "a result line before the error" ;;
  grid_yaml_names)  # a 2D grid's YAML names its image whatever the file name holds (PyYAML reads it back)
    python3 -c 'import yaml' 2> /dev/null || { echo "SKIPPED: python3-yaml (import yaml) is missing"; exit 0; }
    names=('lab #2' 'map: v2' '[old] lab' '#h' '- map' $'new\nline' "'q'" '"dq"' 'a{b}' 'x&y' '*s'
           '!t' '%p' '@a' 'b\c' $'t\tab' 'café' '? q' '|x' '>y' ' lead' 'trail ' $'c1\xc2\x85' $'ls\xe2\x80\xa8')
    for n in "${names[@]}"; do
      expect 0 "" "$K" map --input p.xyz --res 0.1 -o "$n.yaml" --grid-z -1:2 --up z
    done
    python3 - "${names[@]}" <<'PY' || fail "a YAML does not name its image"
import os, sys, yaml
for n in sys.argv[1:]:
    with open(n + ".yaml", encoding="utf-8") as f:
        image = yaml.safe_load(f)["image"]
    assert image == n + ".pgm", (n, image)
    assert os.path.isfile(image), image
print(len(sys.argv) - 1, "YAML files name their images")
PY
    "$K" map --input p.xyz --res 0.1 --out-bt m.bt > /dev/null || fail "map"
    expect 0 "" "$K" convert m.bt $'conv #1\n.yaml' --grid-z -1:2 --up z
    python3 -c 'import yaml; assert yaml.safe_load(open("conv #1\n.yaml"))["image"] == "conv #1\n.pgm"' ||
      fail "convert's YAML"
    expect 2 "bad\\\\xff.yaml: the image name 'bad\\\\xff.pgm' is not valid UTF-8" \
      "$K" map --input p.xyz --res 0.1 -o $'bad\xff.yaml' --grid-z -1:2
    [ -z "$(ls | grep '^bad')" ] || fail "a file of the refused name was written"
    # a view page keeps a name's tab and newline as JSON escapes
    expect 0 "" "$K" view m.bt --names $'tab\there\nnl' -o page.html
    grep -q '"name":"tab\\u0009here\\u000anl"' page.html || fail "the page's name lost its escapes" ;;
  empty_keyframe_with_ids)  # an empty keyframe whose PLY declares `uint id` carries ids
    mkdir -p seq/clouds && printf '0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n' > seq/poses.txt
    for i in 0 1 3; do printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uint id\nend_header\n1 0 0 7\n1 1 0 8\n0 1 1 9\n' > seq/clouds/00000$i.ply; done
    printf 'ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nproperty uint id\nend_header\n' > seq/clouds/000002.ply
    expect 0 "" "$K" map --input seq --res 0.1 --model robust --out-voxels v.txt
    ! grep -q "needs map-point ids" err.txt || fail "robust warned of missing ids"
    "$K" info seq/clouds/000002.ply | grep -q "^ids: yes$" || fail "info: $("$K" info seq/clouds/000002.ply)"
    expect 0 "" "$K" eval --heldout seq --folds 2 --model robust
    grep -q "^heldout robust   folds 2 points 3 recall" out.txt || fail "eval --heldout: $(cat out.txt)"
    expect 0 "" "$K" eval --ids seq
    grep -q "^map_points 3 " out.txt || fail "eval --ids: $(cat out.txt)"
    expect 0 "" "$K" convert seq/clouds/000002.ply copy.ply
    grep -aq "^property uint id" copy.ply || fail "convert dropped the id property of an empty cloud"
    # a cloud without the property among clouds with it: refused as before
    printf 'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 0 0\n' > seq/clouds/000001.ply
    expect 2 "seq/clouds/000001.ply: .*with and without ids" "$K" map --input seq --res 0.1 --model knn
    expect 2 "seq/clouds/000001.ply: no map-point ids" "$K" eval --heldout seq --folds 2 ;;
  heldout_nothing_to_score)  # no point seen by --min-views held-out keyframes: exit 2, no score
    "$K" sim --out seq --seed 3 --keyframes 4 > /dev/null || fail "sim"
    expect 2 "seq: nothing to score: no map point is seen by --min-views 2 held-out keyframes of one fold \(4 keyframes in --folds 4: at most 1 see one point\)" \
      "$K" eval --heldout seq --folds 4 --model octomap
    [ ! -s out.txt ] || fail "a score was printed: $(cat out.txt)"
    expect 2 "seq: nothing to score: no map point is seen by --min-views 9 held-out keyframes" \
      "$K" eval --heldout seq --folds 2 --min-views 9 --model octomap
    [ ! -s out.txt ] || fail "a score was printed: $(cat out.txt)"
    expect 0 "" "$K" eval --heldout seq --folds 2 --model octomap
    expect 2 "seq/poses.txt: is not a folder: a sequence is a folder" "$K" eval --heldout seq/poses.txt
    "$K" map --input seq --res 0.1 --out-bt m.bt > /dev/null || fail "map"
    expect 2 "seq/poses.txt: is not a folder: a sequence is a folder" "$K" eval --map m.bt --ids seq/poses.txt
    expect 2 "nope: sequence folder does not exist" "$K" eval --heldout nope ;;
  errors_name_the_file)  # an oversized 2D grid and running out of memory name the file
    printf -- '-3000 -3000 0.5\n3000 3000 0.5\n' > far.xyz
    expect 2 "^knnocc map: far.yaml: the 2D grid of the height band would have 60001 x 60001 cells" \
      "$K" map --input far.xyz --res 0.1 -o far.yaml --grid-z 0:1 --up z
    [ ! -e far.yaml ] && [ ! -e far.pgm ] || fail "a grid file was written"
    [ -z "${KNNOCC_TOOL_SANITIZED:-}" ] || { echo "SKIPPED: sanitizer build, no address-space limit"; exit 0; }
    printf -- '0 0 0.5\n2000 2000 0.5\n' > wide.xyz
    "$K" map --input wide.xyz --res 0.1 --out-bt wide.bt > /dev/null || fail "map"
    expect 2 "^knnocc convert: wide.yaml: out of memory \(--memory-limit 200 MB\)" \
      "$K" convert wide.bt wide.yaml --grid-z 0:1 --up z --memory-limit 200M
    # A map that fits whose cloud of free voxels does not: the line names the output.
    awk 'BEGIN { for (i = 0; i < 200; i++) for (j = 0; j < 200; j++)
                   printf "%.1f %.1f 8\n", (i - 100) * 0.1, (j - 100) * 0.1 }' > sheet.xyz
    "$K" map --input sheet.xyz --res 0.05 --out-bt sheet.bt > /dev/null || fail "map sheet"
    expect 2 "^knnocc convert: sheet.ply: out of memory \(--memory-limit 200 MB\) writing it" \
      "$K" convert sheet.bt sheet.ply --ply-free --memory-limit 200M
    [ ! -e sheet.ply ] || fail "sheet.ply written"
    no_temporaries ;;
  read_only_output)  # a read-only output is kept, as cp keeps it: exit 2, nothing written
    "$K" map --input p.xyz --res 0.1 --out-bt m.bt > /dev/null || fail "map"
    for f in ro.bt ro.ply ro.html ro.yaml ro.pgm; do echo old > $f; done
    chmod 444 ro.bt ro.ply ro.html ro.pgm
    expect 2 "^knnocc map: ro.bt: is read-only \(--out-bt\); nothing was written" \
      "$K" map --input p.xyz --res 0.1 --out-voxels v.txt --out-bt ro.bt
    expect 2 "^knnocc convert: ro.ply: is read-only \(OUT\)" "$K" convert m.bt ro.ply
    expect 2 "^knnocc view: ro.html: is read-only \(--out\)" "$K" view m.bt -o ro.html
    expect 2 "^knnocc map: ro.pgm: is read-only \(-o\)" "$K" map --input p.xyz --res 0.1 -o ro.yaml --grid-z -1:2
    ln -s ro.bt link.bt
    expect 2 "link.bt: is read-only" "$K" convert m.bt link.bt
    for f in ro.bt ro.ply ro.html ro.yaml ro.pgm; do [ "$(cat $f)" = old ] || fail "$f replaced"; done
    [ ! -e v.txt ] || fail "v.txt written"
    chmod 644 ro.bt && expect 0 "" "$K" convert m.bt ro.bt
    cmp -s m.bt ro.bt || fail "a writable output not replaced"
    no_temporaries ;;
  sigpipe_removes_temporaries)  # SIGPIPE (a closed pipe) mid-run: temporaries removed, as SIGTERM
    killed_mid_run PIPE 141 ;;
  stale_staging_folder_removed)  # a SIGKILLed run's staging folder goes at the next start; a live one stays
    "$K" sim --out big --keyframes 100000 > /dev/null 2>&1 &
    pid=$!
    for i in $(seq 50); do ls -a | grep -q 'big\.tmp-' && break; sleep 0.1; done
    killed=$(ls -a | grep 'big\.tmp-') || fail "no staging folder seen"
    kill -KILL $pid; wait $pid
    [ -d "$killed" ] || fail "SIGKILL left no staging folder to clean"
    mkdir big.tmp-Zz99Yy && touch -d '1 minute ago' big.tmp-Zz99Yy  # a user's folder (0755): kept
    mkdir -m 700 big.tmp-Bk0700 && echo mine > big.tmp-Bk0700/notes.txt  # as mktemp -d makes one:
    touch -d '1 minute ago' big.tmp-Bk0700                               # kept, no staging marker
    "$K" sim --out big --keyframes 100000 > /dev/null 2>&1 &
    pid=$!
    for i in $(seq 50); do [ "$(ls -a | grep -c 'big\.tmp-')" = 4 ] && break; sleep 0.1; done
    live=$(ls -a | grep 'big\.tmp-' | grep -v -e "^$killed\$" -e Zz99Yy -e Bk0700) || fail "no live staging folder"
    sleep 2.2  # older than a second (in whole seconds), but locked
    expect 0 "" "$K" sim --out big --keyframes 3
    [ -f big/poses.txt ] || fail "big/ not written"
    [ "$(stat -c %a big)" = "$(printf '%o' $(( 0777 & ~0$(umask) )))" ] || fail "big/ has mode $(stat -c %a big), not mkdir's"
    [ ! -e "$killed" ] || fail "the killed run's staging folder is still there"
    [ -d "$live" ] || fail "a running writer's staging folder was removed"
    [ -d big.tmp-Zz99Yy ] || fail "a user's folder was removed"
    [ "$(cat big.tmp-Bk0700/notes.txt)" = mine ] || fail "a user's 0700 folder was removed"
    [ ! -e big/.knnocc-staging ] || fail "the staging marker was committed"
    kill -TERM $pid; wait $pid
    rmdir big.tmp-Zz99Yy && rm -r big.tmp-Bk0700
    no_temporaries ;;
  *) fail "unknown case $CASE" ;;
esac
echo PASS
