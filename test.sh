#!/usr/bin/env bash
# The whole test suite, with what it needs: the README's test command, and what CI (.ci/run) runs.
#
#   ./test.sh                    # install what is missing, then every test: Vulkan, GL, and the real tools
#   ./test.sh --without blender  # leave out a part (a comma list of: gl, slurm, openjd, blender, glslang)
#   ./test.sh --list             # the Debian packages each part needs, and the parts; nothing is run
#
# 1. Installs the Debian packages the suite needs when any is missing: as root with apt-get, else through sudo;
#    where neither can, it prints the one line to run and stops (exit status 2) before building anything.
# 2. Runs `cargo test --release --no-fail-fast` on Mesa's lavapipe (WGPU_BACKEND=vulkan, so the GPU tests fail
#    loudly rather than fall back to another adapter), then the GPU tests again on Mesa's llvmpipe through GL,
#    then the tests against the real tools our files go on to (Slurm, openjd-cli, Blender, glslang), each
#    behind a cargo feature that this script turns on.
# 3. Ends with what ran and what did not, and why, and one line "N passed, N failed" over all of it. Every
#    stage runs whatever an earlier one did; the exit status is 0 only when every stage that ran passed.
set -uo pipefail
cd "$(dirname "$0")"

# ---- What each part needs -------------------------------------------------------------------------------
# The suite itself: Mesa's Vulkan driver (lavapipe) and loader; Mesa's GL driver (llvmpipe) and EGL, which
# wgpu's GL backend opens without a display; OpenImageIO's oiiotool (tests/export.rs composites our EXR and PNG
# "over" plates with it) and ffmpeg/ffprobe (videos encoded and decoded back).
pkgs_suite="mesa-vulkan-drivers libvulkan1 libegl1 libegl-mesa0 libgl1-mesa-dri libgles2 openimageio-tools ffmpeg"
# The real tools, behind cargo features (Cargo.toml [features]).
pkgs_slurm="slurm-wlm munge"                 # a one-node cluster (.ci/slurm-up), tests/farm_slurm.rs
pkgs_openjd="python3-venv"                    # openjd-cli from PyPI in a venv, tests/farm_openjd.rs
pkgs_blender="blender python3-numpy"          # Blender headless; its glTF exporter needs numpy, tests/blender.rs
pkgs_glslang="glslang-tools"                  # Khronos' glslangValidator, tests/engine.rs
tools="slurm openjd blender glslang"
# The GPU tests run a second time on GL (the rest need no GPU, or are named in gl_left_out with the reason).
gl_tests="gpu_render objects colors decay degenerate_sources degenerate_curves glare specialised integrators robustness
  camera_reach w_form cli progressive viewer_workflow viewer_ui viewer_faults particles_gpu live_particles farm
  first_picture export chain_jumps"
# These files run on GL only for their GPU tests (the rest of each needs no GPU): file:filter.
gl_filtered="translucent:gpu refine:gpu shipped_frames:on_the_gpu"
# The GPU test files not run on GL, and why.
declare -A gl_left_out=(
  [soak]="3 minutes on GL (it passes there)"
  [engine]="runs SPIR-V through wgpu's passthrough, which only Vulkan has"
  [engine_es]="runs its GLSL ES stages on llvmpipe's GLES through EGL itself, in the first run: WGPU_BACKEND does not change it"
)
# The test files that need no GPU (they pass with no driver at all): nothing to run again on GL.
no_gpu="animation curve_nearest field fuzz_corpus gpu_layout look module_graph particle_files particles scene_files
  shader_cli farm_slurm farm_openjd blender"

usage() { sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'; }

without=""
list_only=0
while [ $# -gt 0 ]; do
  case "$1" in
    --without) without="${2:-}"; shift 2 || { usage >&2; exit 2; } ;;
    --without=*) without="${1#--without=}"; shift ;;
    --list) list_only=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "test.sh: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
for part in ${without//,/ }; do
  case " gl $tools " in
    *" $part "*) ;;
    *) echo "test.sh: --without $part: not a part; the parts are: gl $tools" >&2; exit 2 ;;
  esac
done
left_out() { case ",$without," in *",$1,"*) return 0 ;; *) return 1 ;; esac; }

if [ "$list_only" -eq 1 ]; then
  echo "suite (always): $pkgs_suite"
  echo "gl: the same packages; GPU tests again with WGPU_BACKEND=gl"
  for t in $tools; do v="pkgs_$t"; echo "$t: ${!v}"; done
  exit 0
fi

# ---- 1. Install what is missing ---------------------------------------------------------------------------
wanted="$pkgs_suite"
for t in $tools; do
  left_out "$t" || { v="pkgs_$t"; wanted="$wanted ${!v}"; }
done

missing=""
if command -v dpkg-query >/dev/null 2>&1; then
  for p in $wanted; do
    [ "$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null)" = installed ] || missing="$missing $p"
  done
  missing="${missing# }"
else
  echo "test.sh: not a Debian system (no dpkg-query): the suite needs the equivalents of: $wanted" >&2
fi

if [ -n "$missing" ]; then
  install_line="apt-get update && apt-get install -y $missing"
  if [ "$(id -u)" -eq 0 ]; then
    as_root=()
  elif command -v sudo >/dev/null 2>&1 && { [ -t 0 ] || sudo -n true 2>/dev/null; }; then
    as_root=(sudo)
  else
    echo "test.sh: the suite needs Debian packages that are not installed, and this user can neither install them" >&2
    echo "(not root, no usable sudo). Run, as root:" >&2
    echo "  $install_line" >&2
    echo "then ./test.sh again (or leave parts out: ./test.sh --without $(echo "$tools" | tr ' ' ',')). Nothing was built or run." >&2
    exit 2
  fi
  echo "test.sh: installing${as_root:+ through sudo}: $missing"
  export DEBIAN_FRONTEND=noninteractive
  if ! "${as_root[@]}" apt-get update -qq || ! "${as_root[@]}" apt-get install -y -qq --no-install-recommends $missing >/dev/null; then
    echo "test.sh: installing the packages failed (see apt-get's message above). Run, as root:" >&2
    echo "  $install_line" >&2
    exit 2
  fi
fi

# ---- 2. Run ---------------------------------------------------------------------------------------------
export WGPU_BACKEND=vulkan
if [ -z "${XDG_RUNTIME_DIR:-}" ] || [ ! -w "${XDG_RUNTIME_DIR}" ]; then
  XDG_RUNTIME_DIR="$(mktemp -d)"
  export XDG_RUNTIME_DIR
fi
logs="target/test-logs"
mkdir -p "$logs"
rm -f "$logs"/*.log

summary=()   # one line a stage
all_passed=0
all_failed=0
all_ignored=0
status=0

# run_stage NAME LOG COMMAND...: runs the command, its output to the terminal and to LOG; adds its counts.
run_stage() {
  local name="$1" log="$logs/$2.log"
  shift 2
  echo
  echo "==== $name: $*"
  "$@" 2>&1 | tee "$log"
  local rc=${PIPESTATUS[0]}
  local counts passed failed ignored
  # cargo's "test result: ok. 12 passed; 0 failed; 1 ignored; ..." per test binary.
  counts=$(sed -n 's/^test result: [a-zA-Z]*\. \([0-9]*\) passed; \([0-9]*\) failed; \([0-9]*\) ignored.*/\1 \2 \3/p' "$log" |
    awk '{p += $1; f += $2; i += $3} END {print p + 0, f + 0, i + 0}')
  read -r passed failed ignored <<<"$counts"
  all_passed=$((all_passed + passed))
  all_failed=$((all_failed + failed))
  all_ignored=$((all_ignored + ignored))
  local line="$name: $passed passed, $failed failed, $ignored ignored"
  if [ "$rc" -ne 0 ]; then
    status=1
    # With --no-fail-fast cargo names the test binaries that failed at the end; a build error names none.
    local targets
    targets=$(sed -n 's/^    `\(.*\)`$/\1/p' "$log" | tr '\n' ' ')
    if [ -n "$targets" ]; then
      line="$line; FAILED: $targets"
    else
      line="$line; FAILED (exit status $rc, see $log)"
      [ "$failed" -gt 0 ] || all_failed=$((all_failed + 1))
    fi
  fi
  summary+=("$line")
}

cargo --version

# Before ten minutes of failures: is there an adapter at all?
if cargo build --release --quiet && ! target/release/energywave render --size 8x8 --resolution 8 \
  --output "$XDG_RUNTIME_DIR/adapter-check.png" >/dev/null 2>"$XDG_RUNTIME_DIR/adapter-check.err"; then
  echo "test.sh: energywave cannot render on the GPU here, so every GPU test would fail:" >&2
  cat "$XDG_RUNTIME_DIR/adapter-check.err" >&2
  exit 1
fi

run_stage "suite on Vulkan (lavapipe)" vulkan cargo test --release --no-fail-fast

if left_out gl; then
  summary+=("GL (llvmpipe): left out (--without gl)")
else
  args=()
  for t in $gl_tests; do args+=(--test "$t"); done
  WGPU_BACKEND=gl run_stage "GPU tests on GL (llvmpipe)" gl cargo test --release --no-fail-fast "${args[@]}"
  for tf in $gl_filtered; do
    before=$all_passed
    WGPU_BACKEND=gl run_stage "GPU tests of tests/${tf%%:*}.rs on GL" "gl-${tf%%:*}" \
      cargo test --release --no-fail-fast --test "${tf%%:*}" "${tf#*:}"
    # A filter that names no test (a test renamed) would run none and pass: it must run some.
    if [ "$all_passed" -eq "$before" ]; then
      summary+=("  FAILED: the filter '${tf#*:}' ran no test of tests/${tf%%:*}.rs on GL: rename it in gl_filtered")
      status=1
      all_failed=$((all_failed + 1))
    fi
  done
  # Every GPU test file that is not on the GL list, and why: none is left out silently, and a new test file
  # must be put on a list.
  for f in tests/*.rs; do
    t=$(basename "$f" .rs)
    case " $(echo $gl_tests $no_gpu $(for tf in $gl_filtered; do echo "${tf%%:*}"; done)) " in *" $t "*) continue ;; esac
    if [ -n "${gl_left_out[$t]:-}" ]; then
      summary+=("  not on GL: tests/$t.rs: ${gl_left_out[$t]}")
    else
      summary+=("  FAILED: tests/$t.rs is on no list of test.sh (gl_tests, gl_left_out or no_gpu): say where it runs")
      status=1
      all_failed=$((all_failed + 1))
    fi
  done
fi

# ---- The real tools -------------------------------------------------------------------------------------
features=()
tool_tests=()
declare -A tool_test=([slurm]=farm_slurm [openjd]=farm_openjd [blender]=blender [glslang]=engine)
for t in $tools; do
  if left_out "$t"; then
    summary+=("$t (tests/${tool_test[$t]}.rs): left out (--without $t)")
    continue
  fi
  case "$t" in
    slurm)
      if ! .ci/slurm-up; then
        summary+=("slurm (tests/farm_slurm.rs): FAILED: the one-node cluster did not come up (.ci/slurm-up above)")
        status=1
        continue
      fi
      ;;
    openjd)
      venv="target/openjd-venv"
      if ! "$venv/bin/openjd" --version >/dev/null 2>&1; then
        rm -rf "$venv"
        if ! { python3 -m venv "$venv" && "$venv/bin/pip" install -q openjd-cli==0.8.0; }; then
          summary+=("openjd (tests/farm_openjd.rs): FAILED: openjd-cli 0.8.0 could not be installed from PyPI")
          status=1
          continue
        fi
      fi
      # After the system's own: Blender's Python, started with the venv's python3 first on PATH, takes the
      # venv for its prefix and no longer finds Debian's numpy.
      export PATH="$PATH:$PWD/$venv/bin"
      ;;
  esac
  features+=("$t")
  tool_tests+=(--test "${tool_test[$t]}")
done
if [ ${#features[@]} -gt 0 ]; then
  feature_list=$(IFS=,; echo "${features[*]}")
  run_stage "real tools ($feature_list)" tools cargo test --release --no-fail-fast --features "$feature_list" "${tool_tests[@]}"
fi

# ---- 3. What ran ----------------------------------------------------------------------------------------
echo
echo "==== test.sh: what ran"
for line in "${summary[@]}"; do echo "$line"; done
echo "logs: $logs/"
echo "$all_passed passed, $all_failed failed, $all_ignored ignored"
exit "$status"
