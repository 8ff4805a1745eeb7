#!/usr/bin/env bash
# Installs what is needed, builds, and runs every test:
#   1. the GoogleTest suites and integration tests with Debian's MRPT apps (Release build);
#   2. the unit suites again under AddressSanitizer + UndefinedBehaviorSanitizer (clang);
#   3. the libFuzzer targets from the same build: the Nexmon parser + frame assembler, one per
#      CSI file decoder (nexmon, intel5300, esp32, atheros), WiROS's ROS messages and the
#      localization programs' text inputs (bearings CSV, trajectories, AP map YAML, .ini values),
#      FUZZ_SECONDS split between them.
# Ends with one line "summary: N passed, N failed". Exit code non-zero if anything failed.
set -uo pipefail
cd "$(dirname "$0")/.."
FUZZ_SECONDS=${FUZZ_SECONDS:-40}  # a smoke run in CI; longer runs: docs/evaluation.md

bash scripts/install-deps.sh || exit 1
passed=0
failed=0
count_ctest() {  # adds ctest's "N% tests passed, F tests failed out of T" to the totals
  local line total bad
  line=$(grep -E "tests passed, [0-9]+ tests? failed out of [0-9]+" "$1" | tail -1)
  total=$(sed -E 's/.*out of ([0-9]+).*/\1/' <<<"$line")
  bad=$(sed -E 's/.*passed, ([0-9]+) tests? failed.*/\1/' <<<"$line")
  if [ -z "$line" ]; then failed=$((failed + 1)); return; fi
  passed=$((passed + total - bad)); failed=$((failed + bad))
}

# A clean clone has no CTest cost data, so ctest would run the tests in number order and start
# the longest ones (numbered late) last, one core idle meanwhile. Their measured seconds are
# seeded instead ("name runs seconds"); ctest replaces the file with its own after the run.
seed_test_costs() {  # BUILD_DIR "NAME SECONDS" ...
  local file=$1/Testing/Temporary/CTestCostData.txt; shift
  [ -f "$file" ] && return 0
  mkdir -p "$(dirname "$file")"
  { for entry in "$@"; do awk '{print $1, 1, $2}' <<<"$entry"; done; echo "---"; } >"$file"
}

echo "== [1/3] Release build and all tests"
if bash scripts/build.sh; then
  seed_test_costs build "LocalizationAccuracy.EvaluatesOneRoomEndToEnd 182" \
    "LocalizationAccuracy.WithAodCalibratesEveryApAndUsesItsAod 72" \
    "Docs.RobotGuideRunsOnTheEmulator 69" \
    "LocalizationAppsPf.WithoutOdometryWithinOneAndAHalfTimesTheOdometryError 28" \
    "WifiLocalize.UsesTheCsiSensorsOwnLiveBearings 25" "WifiLocalize.ReplayingACaptureGivesTheOfflineEstimate 25" \
    "WifiLocalize.LocalizesTheKidnappedRobotLiveFromTheEmulator 24" \
    "LocalizationAppsGraphSlam.KnownApsAoaOnlyPipelineSeed41 23" \
    "LocalizationAppsPf.FindsTheRobotAgainAfterAKidnappingMidRun 21" "Docs.RouterGuideRunsOnTheEmulator 21"
  # Three jobs on CI's two cores: many integration tests wait on real-time streams (the
  # emulator at its frame rate, live runs, the guides' recordings) and a third job fills that
  # time (ctest 557 s with -j2, 426 s with -j3 on two cores, the same 549 tests passing).
  ctest --test-dir build --output-on-failure -j3 --timeout 600 2>&1 | tee build/ctest.log
  count_ctest build/ctest.log
else
  echo "Release build FAILED"; failed=$((failed + 1))
fi

echo "== [2/3] ASan + UBSan build (clang), unit suites"
# One instrumented clang build serves the unit suites and the fuzz targets: the libraries carry
# libFuzzer's coverage hooks (-fsanitize=fuzzer-no-link), which cost the unit suites ~30 s, and
# only the fuzz executables link libFuzzer's main. (A separate fuzz build took ~5 min of CI's 30.)
# Integration tests load our (instrumented) plugin into Debian's uninstrumented MRPT apps, which
# ASan does not allow: they ran in step 1. Line tables only (-g1): ASan's reports keep
# file:line, and the build takes much less time than with full debug information.
debug_lines=(-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG")
# Step 1 runs these long drives; instrumented they would take 25-90 s each (CI's 30 minutes):
# the three end-to-end transmit-chain calibrations (the calibration file's code runs in
# TxCalibrationFile) and one of the window smoother's two no-odometry drives (the other runs).
asan_skip="TxChainCalibration[.](AodOnlyWhereCalibratedAndHonestSigma|ReceiverFromDriftingOdometryWithin3Degrees|RecoversInjectedOffsetsFromTruePoses)|WindowSmoother[.]WithoutOdometryFitsATrackToTheBearings"
asan_targets="test_obs test_sensor_decoding test_csi_sources test_live_sources test_driver_units test_live_bearings test_emulator_unit test_live_units test_sim test_bearings test_source_bearings test_calib test_tx_calib test_localization test_sar test_input_robustness"
# The decoders' length-check seeds and the text readers' seeds, replayed instrumented
# (FuzzSeeds.*).
asan_targets="$asan_targets fuzz_make_seeds fuzz_replay_nexmon fuzz_replay_intel5300 fuzz_replay_esp32 fuzz_replay_atheros fuzz_replay_rosmessages fuzz_replay_rosbag2 fuzz_replay_textinputs"
# The fuzz time is split evenly between the targets (the assembler, one per file decoder, the
# ROS 1 messages, the ROS 2 bag reader, the localization programs' text readers), so the total
# stays FUZZ_SECONDS.
fuzz_targets="fuzz_nexmon_assembler fuzz_decoder_nexmon fuzz_decoder_intel5300 fuzz_decoder_esp32 fuzz_decoder_atheros fuzz_ros_messages fuzz_rosbag2 fuzz_text_inputs"
san_built=false
if CC=clang CXX=clang++ cmake -S . -B build-san -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "${debug_lines[@]}" \
     -DMRPT_WIFI_SANITIZE=ON -DMRPT_WIFI_FUZZ=ON -DMRPT_WIFI_BUILD_BENCHMARKS=OFF \
     -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link" >/dev/null &&
   cmake --build build-san -j"$(nproc)" --target $asan_targets $fuzz_targets; then
  san_built=true
  seed_test_costs build-san "GraphSlamUnknownAps.ApCovarianceCoversMultipathAndOdometryBias 23" \
    "GraphSlamUnknownAps.SurvivesStrongHeadingDriftOverFiveLaps 14" "CsiSourcesCli.ImportAndExportEveryFormat 10" \
    "RandomRoom.EveryLoopKeepsClearOfTheFurniture 9" "GraphSlamKnownAps.AoaOnlyKnownApsNeverWorseThanEstimated 8"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-san --output-on-failure -j2 -L "unit|sim|bearings|calib|localization" \
      -LE integration -E "_NOT_BUILT|$asan_skip" --timeout 900 2>&1 | tee build-san/ctest.log
  count_ctest build-san/ctest.log
else
  echo "ASan build FAILED"; failed=$((failed + 1))
fi

n_fuzz_targets=$(wc -w <<<"$fuzz_targets")
per_target=$(( FUZZ_SECONDS / n_fuzz_targets > 0 ? FUZZ_SECONDS / n_fuzz_targets : 1 ))
echo "== [3/3] libFuzzer: Nexmon assembler, nexmon/intel5300/esp32/atheros decoders, ROS messages, ROS 2 bags, text inputs: ${per_target} s each"
if $san_built; then
  for target in $fuzz_targets; do
    corpus=build-san/corpus-$target
    rm -rf "$corpus"; mkdir -p "$corpus"
    case $target in
      fuzz_nexmon_assembler) build-san/bin/fuzz_make_seeds "$corpus" ;;
      fuzz_decoder_nexmon) cp tests/data/nexmon/*.pcap "$corpus"/ && build-san/bin/fuzz_make_seeds "$corpus" nexmon tests/data ;;
      fuzz_decoder_intel5300) cp tests/data/intel5300/*.dat "$corpus"/ && build-san/bin/fuzz_make_seeds "$corpus" intel5300 tests/data ;;
      fuzz_decoder_esp32) cp tests/data/esp32/csi_data.csv "$corpus"/ && build-san/bin/fuzz_make_seeds "$corpus" esp32 tests/data ;;
      fuzz_decoder_atheros) cp tests/data/atheros/*.dat "$corpus"/ && build-san/bin/fuzz_make_seeds "$corpus" atheros tests/data ;;
      fuzz_ros_messages) build-san/bin/fuzz_make_seeds "$corpus" rosmessages tests/data ;;
      fuzz_rosbag2) build-san/bin/fuzz_make_seeds "$corpus" rosbag2 tests/data ;;
      fuzz_text_inputs) build-san/bin/fuzz_make_seeds "$corpus" text share ;;
    esac
    # tests/fuzz/fuzz_csi_decoder.cpp says why non-capture inputs are read as this project's
    # class only (MRPT's other classes allocate whatever a damaged count claims).
    if build-san/bin/$target -max_total_time="$per_target" -max_len=20000 \
         -print_final_stats=1 "$corpus" >build-san/$target.log 2>&1; then
      tail -3 build-san/$target.log; echo "fuzz $target: no crash in ${per_target} s"; passed=$((passed + 1))
    else
      tail -40 build-san/$target.log; echo "fuzz $target: FAILED"; failed=$((failed + 1))
    fi
  done
else
  echo "fuzz targets not built (see the ASan build above)"; failed=$((failed + 1))
fi

echo "summary: ${passed} passed, ${failed} failed"
[ "$failed" -eq 0 ]
