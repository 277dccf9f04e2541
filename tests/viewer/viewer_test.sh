#!/usr/bin/env bash
# One `afterglow view` test under a virtual X server (docs/viewer.md, "Tests").
#   viewer_test.sh script|replay AFTERGLOW VIEWER_CHECK OUT_DIR
# Exit 0 passed, 1 failed, 77 skipped (no xvfb-run, or no GL 4.5 window under Xvfb): CTest's
# SKIP_RETURN_CODE, so a machine that cannot run the viewer never reports it as passed.
set -u
test_name=$1 afterglow=$2 check=$3 out=$4

if ! command -v xvfb-run > /dev/null; then
    echo "SKIPPED: xvfb-run not found (Debian package xvfb)"
    exit 77
fi
rm -rf "$out"
mkdir -p "$out"

# Runs the viewer; a window that cannot be made is a skip, any other failure a failure.
view() {
    xvfb-run -a -s "-screen 0 1280x1024x24" "$afterglow" view "$@" > "$out/stdout.txt" 2> "$out/stderr.txt"
    local rc=$?
    cat "$out/stderr.txt"
    if [ $rc -ne 0 ]; then
        if grep -q "error: window:" "$out/stderr.txt"; then
            echo "SKIPPED: no GL 4.5 core window under Xvfb (see the error above)"
            exit 77
        fi
        echo "FAILED: afterglow view exited with $rc"
        exit 1
    fi
}

failed=0
expect() {
    echo "+ $*"
    "$@" || failed=1
}

case $test_name in
    script)
        # cornell_move_cube.lua slides the cube from the right of the floor to the front left
        # over frames 1-60; the viewer exits 30 frames after its last edit.
        view scenes/cornell.json --script scenes/cornell_move_cube.lua --frames 120 --size 256x256 \
            --shots "$out" --exit-after-script --dump "$out/dump.json"
        expect "$check" not-blank "$out/first.png"
        expect "$check" not-blank "$out/last.png"
        # The cube's shadow on the floor right of its start (towards the green wall) is lit at the end...
        expect "$check" changed "$out/first.png" "$out/last.png" 0.78 0.89 0.88 0.97 0.2
        # ...and where the cube arrived the frame got darker, although indirect light brightened
        # everything else since frame 0.
        expect "$check" changed "$out/first.png" "$out/last.png" 0.125 0.75 0.25 0.875 -0.05
        if grep -q "exiting" "$out/stderr.txt"; then :; else
            echo "FAILED: --exit-after-script did not end the run before --frames"
            failed=1
        fi
        ;;
    replay)
        # Clicks the cube at frame 2, drags it 60 pixels left by frame 13, turns it (R), switches
        # views and takes screenshots (F12, Shift+F12).
        view scenes/cornell.json --replay tests/viewer/drag_cube.json --frames 60 --size 256x256 \
            --shots "$out" --dump "$out/dump.json"
        expect "$check" dragged "$out/dump.json" cube 50 1
        for shot in first.png last.png shot_00021.png shot_00023.png window_00040.png; do
            expect "$check" not-blank "$out/$shot"
        done
        ;;
    photon_tiles)
        # gpu_pm's photon-tile view from the first frame (docs/gpu_pm.md): a picture, not black.
        view scenes/cornell.json --indirect gpu_pm --view photon_tiles --frames 6 --size 128x128 \
            --shots "$out" --set gpu_pm.paths=500
        expect "$check" not-blank "$out/first.png"
        expect "$check" not-blank "$out/last.png"
        ;;
    media)
        # The media view: a slice of the media method's fluence grid through the glass sphere in
        # fog (docs/media.md); black if the pipeline ran no media method or the slice is empty.
        view scenes/media_glass_fog_point.json --view media --frames 2 --size 64x64 \
            --shots "$out"
        expect "$check" not-blank "$out/last.png"
        ;;
    vpls)
        # The VPL view (docs/vpl.md): the VPL sum with the VPLs drawn over it as points, against
        # the indirect view of the same run: not blank, and the points add light.
        view scenes/cornell.json --indirect vpl --view indirect --frames 6 --size 128x128 \
            --set vpl.map_size=32 --shots "$out/indirect"
        view scenes/cornell.json --indirect vpl --view vpls --frames 6 --size 128x128 \
            --set vpl.map_size=32 --shots "$out/vpls"
        expect "$check" not-blank "$out/vpls/last.png"
        expect "$check" changed "$out/indirect/last.png" "$out/vpls/last.png" 0 0 1 1 0.005
        ;;
    *)
        echo "unknown viewer test '$test_name'"
        exit 2
        ;;
esac
[ $failed -eq 0 ] && echo "PASSED" || echo "FAILED"
exit $failed
