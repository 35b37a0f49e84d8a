#!/usr/bin/env bash
# The prepared GPU check of issue 31, one device call: (a) the GPU tests of `cargo test`
# (prebuilt release test binaries) and pytest, (b) every method and ispm estimator on the
# built-in scenes against lavapipe references (mean and FLIP), (c) frame_bench at 1920x1080
# and 1280x720 with the GPU timestamp split per stage (ispm, each estimator; bidir).
# Each part has a time limit; a part cut off is reported as TIMED OUT, work never started
# as NOT RUN, never as passed. Everything goes to one folder; a compact summary and an
# archive of the folder go to the returned folder ($OUT on the device machine).
#
# It runs from the bundle that scripts/ci/gpu_bundle.sh prepares (.gpu/, .whl/, .gl/ in the
# repository root); docs/gpu-check.md has the device call and how to read the outputs.
#
#   bash .gpu/gpu_check.sh                  # on the GPU machine (GI_ADAPTER=gpu)
#   bash .gpu/gpu_check.sh --smoke          # here, on lavapipe, small sizes (a few minutes)
#
# Options: --smoke, --out DIR (everything; default /tmp/gpu-check), --ret DIR (the returned
# files; default $OUT when set), --parts a,b,c, --budget SECONDS (whole run, default 510),
# --adapter gpu|cpu, --python EXE, --wheels DIR, --sizes "WxH ...", --photons "N ...",
# --runs N; part p (not in the default parts) runs each probe in the bundle's probes/ (from
# scripts/probe/gpu_probes/: `python PROBE OUTDIR`, for a question a failure raised) within
# GPU_CHECK_PROBES_S (120); the parts' limits from GPU_CHECK_CARGO_S (110), GPU_CHECK_PYTEST_S (90) and
# GPU_CHECK_IMAGES_S (75), pytest workers from GPU_CHECK_WORKERS (4); frame_bench gets the rest.
set -euo pipefail
trap 'echo "gpu_check: line $LINENO failed: $BASH_COMMAND" >&2' ERR

bundle=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(dirname "$bundle")
smoke=0 out=/tmp/gpu-check ret=${OUT:-} parts=a,b,c budget=510 adapter="" python=""
wheels="" sizes="" photons="" runs=""
while [ $# -gt 0 ]; do
  case $1 in
    --smoke) smoke=1 ;;
    --out) out=$2; shift ;;
    --ret) ret=$2; shift ;;
    --parts) parts=$2; shift ;;
    --budget) budget=$2; shift ;;
    --adapter) adapter=$2; shift ;;
    --python) python=$2; shift ;;
    --wheels) wheels=$2; shift ;;
    --sizes) sizes=$2; shift ;;
    --photons) photons=$2; shift ;;
    --runs) runs=$2; shift ;;
    -h | --help) sed -n '2,23p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "gpu_check: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
if [ "$smoke" = 1 ]; then
  adapter=${adapter:-cpu} sizes=${sizes:-160x120} photons=${photons:-"2000 5000"} runs=${runs:-1}
  python=${python:-$root/target/gpu-smoke/venv/bin/python} wheels=${wheels:-$root/target/gpu-smoke/whl}
else
  adapter=${adapter:-gpu} sizes=${sizes:-"1920x1080 1280x720"}
  photons=${photons:-"20000 50000 200000"} runs=${runs:-3} python=${python:-python3}
  wheels=${wheels:-$root/.whl}
fi
out=$(realpath -m "$out") wheels=$(realpath -m "$wheels")
case $python in */*) python=$(realpath -ms "$python") ;; esac # a venv's link kept
[ -z "$ret" ] || ret=$(realpath -m "$ret")
# Seconds per part, of the budget: (a) cargo tests, pytest; (b) images; (c) the rest.
budget_cargo=${GPU_CHECK_CARGO_S:-110} budget_pytest=${GPU_CHECK_PYTEST_S:-90}
budget_images=${GPU_CHECK_IMAGES_S:-75} budget_probes=${GPU_CHECK_PROBES_S:-120}
start=$SECONDS
deadline=$((start + budget))

[ -f "$bundle/BUNDLE" ] || { echo "gpu_check: $bundle is not a bundle (run scripts/ci/gpu_bundle.sh)" >&2; exit 2; }
rm -rf "$out"
mkdir -p "$out/logs"
# die MESSAGE: stops the check, with the logs so far in the returned folder.
die() {
  log "$*"
  if [ -n "$ret" ]; then mkdir -p "$ret" && tar -czf "$ret/gpu-check.tar.gz" -C "$out" .; fi
  exit 2
}
status=$out/status.tsv
printf 'part\tstatus\tseconds\tdetail\n' >"$status"
log() { echo "[gpu_check $((SECONDS - start))s] $*" | tee -a "$out/logs/check.log"; }
# record PART STATUS SECONDS DETAIL
record() { printf '%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$4" >>"$status"; log "$1: $2 ($3 s) $4"; }
left() { echo $((deadline - SECONDS)); }
# timed LIMIT LOG [--err ERRLOG] CMD...: runs CMD with a time limit, its output to LOG
# (standard error too, unless to ERRLOG); sets rc and took. At the limit CMD gets SIGINT
# (pytest then still writes its report), 10 s later SIGKILL.
timed() {
  local limit=$1 logf=$2 errf=$2; shift 2
  if [ "$1" = --err ]; then errf=$2; shift 2; fi
  local t0=$SECONDS
  set +e
  if [ "$errf" = "$logf" ]; then
    timeout -s INT --kill-after=10 "$limit" "$@" >"$logf" 2>&1
  else
    timeout -s INT --kill-after=10 "$limit" "$@" >"$logf" 2>"$errf"
  fi
  rc=$?
  set -e
  took=$((SECONDS - t0))
}
verdict_of() { # rc -> ok / FAILED (rc N) / TIMED OUT
  case $1 in 0) echo ok ;; 124 | 137) echo "TIMED OUT" ;; *) echo "FAILED (rc $1)" ;; esac
}

cp "$bundle/BUNDLE" "$out/BUNDLE"
log "bundle: $(head -1 "$bundle/BUNDLE"); mode: $([ $smoke = 1 ] && echo smoke || echo full); adapter: $adapter; budget ${budget}s"

# --- Environment: the Vulkan loader where there is none (root only), the NVIDIA ICD, wheels.
if [ "$smoke" = 0 ] && ! ldconfig -p 2>/dev/null | grep 'libvulkan\.so\.1' >/dev/null; then
  [ -d "$root/.gl" ] || die "no libvulkan.so.1 and no .gl/ to unpack"
  log "unpacking the Vulkan loader from .gl/"
  for f in "$root"/.gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ "$adapter" = gpu ] && [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$icd" ] &&
  ! ls /usr/share/vulkan/icd.d/nvidia_icd*.json /etc/vulkan/icd.d/nvidia_icd*.json >/dev/null 2>&1; then
  export VK_DRIVER_FILES=$icd
  log "VK_DRIVER_FILES=$icd"
fi
export GI_ADAPTER=$adapter PYTHONUNBUFFERED=1 PYTHONDONTWRITEBYTECODE=1
site=$(mktemp -d /tmp/gi-site.XXXXXX)
"$python" -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target "$site" "$wheels"/*.whl \
  >"$out/logs/pip.log" 2>&1 || { cat "$out/logs/pip.log"; die "installing the wheels failed"; }
export PYTHONPATH=$site${PYTHONPATH:+:$PYTHONPATH} PATH=$site/bin:$PATH
"$python" - >"$out/adapter.txt" 2>&1 <<EOF || { cat "$out/adapter.txt"; die "no adapter for GI_ADAPTER=$adapter"; }
import gi, sys
assert gi.__file__.startswith("$site"), f"gi from {gi.__file__}, not the bundle's wheel"
print("gi", gi.__version__, "python", sys.version.split()[0])
print(gi.adapter_report())
EOF
tee -a "$out/logs/check.log" <"$out/adapter.txt"
if command -v nvidia-smi >/dev/null; then nvidia-smi -L >>"$out/adapter.txt" 2>&1 || true; fi

has() { [[ ",$parts," == *",$1,"* ]]; }

# --- (a) cargo test binaries, then pytest.
if has a; then
  part_end=$((SECONDS + budget_cargo))
  mkdir -p "$out/cargo"
  failed=0 notrun=0 timedout=0 t0=$SECONDS
  tests=$(mktemp -d /tmp/gi-tests.XXXXXX)
  "$python" -c 'import sys, tarfile; tarfile.open(sys.argv[1]).extractall(sys.argv[2], filter="tar")' \
    "$bundle/tests.tar.xz" "$tests" || die "cannot unpack tests.tar.xz"
  for bin in "$tests"/tests/*; do
    name=$(basename "$bin")
    limit=$((part_end - SECONDS))
    if [ "$limit" -lt 5 ]; then
      echo "NOT RUN (budget)" >"$out/cargo/$name.log"; notrun=$((notrun + 1)); continue
    fi
    # Smoke: each binary starts and lists its tests, and the filter of the bundle runs.
    if [ "$smoke" = 1 ]; then
      timed "$limit" "$out/cargo/$name.log" "$bin" --list
      filt=$(grep -s "^$name " "$bundle/smoke_tests.txt" | cut -d' ' -f2- || true)
      if [ "$rc" = 0 ] && [ -n "$filt" ]; then
        [ "$filt" = "*" ] && filt=""
        # shellcheck disable=SC2086
        timed "$((part_end - SECONDS))" "$out/cargo/$name.log" "$bin" $filt
      fi
    else
      timed "$limit" "$out/cargo/$name.log" "$bin"
    fi
    echo "rc $rc, ${took}s" >>"$out/cargo/$name.log"
    case $rc in 0) ;; 124 | 137) timedout=$((timedout + 1)) ;; *) failed=$((failed + 1)) ;; esac
  done
  st=ok
  [ $failed = 0 ] || st="FAILED"
  [ $timedout = 0 ] || st="TIMED OUT"
  [ $notrun = 0 ] || { st=${st#ok}; st="$st${st:+; }NOT RUN: $notrun binaries"; }
  record cargo-tests "$st" $((SECONDS - t0)) "$failed failed, $timedout timed out"

  # pytest: the suite less what needs packages the machine lacks (listed in the summary);
  # tests that ask for adapter="cpu" (lavapipe) are reported as skipped "needs lavapipe"
  # where there is none (gpu_pytest_plugin.py).
  exclude=(test_animation.py test_batch.py test_notebook.py test_wheel.py test_stubs.py test_denoise.py
    test_fuzz.py test_view.py)
  args=()
  for f in "${exclude[@]}"; do args+=(--ignore="$bundle/pytests/tests/$f"); done
  # Writes an mp4 through imageio-ffmpeg, as test_animation.py does.
  deselect=(test_first_use.py::test_odd_video_sizes_are_padded_with_a_warning)
  for t in "${deselect[@]}"; do args+=(--deselect="tests/$t"); done
  if "$python" -c "import xdist" 2>/dev/null; then args+=(-p xdist.plugin -n "${GPU_CHECK_WORKERS:-4}"); fi
  [ "$smoke" = 1 ] && args+=(-k "$(cat "$bundle/smoke_pytest.txt")")
  limit=$(( budget_pytest < $(left) ? budget_pytest : $(left) ))
  timed "$limit" "$out/logs/pytest.log" env -C "$bundle/pytests" PYTEST_DISABLE_PLUGIN_AUTOLOAD=1 \
    PYTHONPATH="$bundle:$PYTHONPATH" "$python" -m pytest -v -rs -p pytest_timeout \
    -p gpu_pytest_plugin -p _hypothesis_pytestplugin --timeout 60 -o cache_dir=/tmp/gi-pytest-cache \
    --junitxml "$out/pytest.xml" "${args[@]}" tests
  # pytest exits 1 when a test failed: the summary counts them from the XML.
  record pytest "$(verdict_of "$rc")" "$took" "excluded: ${exclude[*]} ${deselect[*]}"
fi

# --- (b) every method and estimator against the lavapipe references.
if has b; then
  limit=$(( budget_images < $(left) ? budget_images : $(left) ))
  cases=()
  [ "$smoke" = 1 ] && read -r -a cases <"$bundle/smoke_images.txt"
  timed "$limit" "$out/logs/images.log" "$python" "$bundle/gpu_images.py" compare \
    --refs "$bundle/refs" --out "$out/images" ${cases[@]+--cases "${cases[@]}"}
  record images "$(verdict_of "$rc")" "$took" "$(tail -1 "$out/logs/images.log")"
fi

# --- (p) probes: diagnostics for a question a failure raised (scripts/probe/gpu_probes/), each
# writing into its own folder of the output.
if has p; then
  t0=$SECONDS failed=0 n=0
  for probe in "$bundle"/probes/*.py; do
    [ -e "$probe" ] || continue
    name=$(basename "$probe" .py) n=$((n + 1))
    limit=$(( budget_probes - (SECONDS - t0) < $(left) ? budget_probes - (SECONDS - t0) : $(left) ))
    mkdir -p "$out/probes/$name"
    timed "$limit" "$out/logs/probe-$name.log" "$python" "$probe" "$out/probes/$name"
    log "probe $name: $(verdict_of $rc) (${took}s)"
    [ $rc = 0 ] || failed=$((failed + 1))
  done
  record probes "$([ $failed = 0 ] && echo ok || echo FAILED)" $((SECONDS - t0)) "$failed of $n failed"
fi

# --- (c) frame_bench: each invocation its own process and time limit, most wanted first.
if has c; then
  mkdir -p "$out/frame"
  read -r -a size_list <<<"$sizes"
  read -r -a photon_list <<<"$photons"
  pargs=()
  for p in "${photon_list[@]}"; do pargs+=(--photons "$p"); done
  jobs=()
  for s in "${size_list[@]}"; do
    # The direct light per kind of light (issue 28: area, sun and sky against a point light).
    jobs+=("lights-$s|--lights --size $s")
    jobs+=("ispm-tiled-$s|--estimator tiled --size $s --stages --table-only")
    # Issue 45 item 1: the photons traced on the CPU and on the GPU, side by side.
    jobs+=("ispm-trace-$s|--estimator tiled --size $s --stages --table-only --no-one-shot --photon-trace cpu --photon-trace gpu")
    jobs+=("instancing-$s|--instancing --size $s") # issue 33: instanced vs flattened, culling
    jobs+=("bidir-$s|--method bidir --size $s")
    for e in volumes cluster directional cpu; do
      jobs+=("ispm-$e-$s|--estimator $e --size $s --stages --table-only --no-one-shot")
    done
  done
  failed=0 timedout=0 notrun=0 t0=$SECONDS
  # The GPU photon trace against the CPU's, with its cold compile (docs/bench/gpu-photon.md).
  if [ -x "$bundle/gpu_photon_bench" ]; then
    pb=$([ "$smoke" = 1 ] && echo 5000 || echo 200000)
    timed "$(( 60 < $(left) ? 60 : $(left) ))" "$out/frame/gpu-photon.md" --err "$out/logs/gpu-photon.err" \
      env MESA_SHADER_CACHE_DISABLE=true __GL_SHADER_DISK_CACHE=0 "$bundle/gpu_photon_bench" --photons "$pb"
    echo "<!-- rc $rc, ${took}s: $(verdict_of $rc) -->" >>"$out/frame/gpu-photon.md"
    log "gpu_photon_bench: $(verdict_of $rc) (${took}s)"
    case $rc in 0) ;; 124 | 137) timedout=$((timedout + 1)) ;; *) failed=$((failed + 1)) ;; esac
  fi
  for j in "${jobs[@]}"; do echo "${j%%|*}"; done >"$out/frame/jobs.txt"
  for j in "${jobs[@]}"; do
    name=${j%%|*} jargs=${j#*|}
    limit=$(($(left) - 25))
    if [ "$limit" -lt 10 ]; then
      echo "NOT RUN (budget)" >"$out/frame/$name.md"; notrun=$((notrun + 1)); continue
    fi
    # shellcheck disable=SC2086
    timed "$limit" "$out/frame/$name.md" --err "$out/logs/frame-$name.err" \
      "$bundle/frame_bench" --runs "$runs" $jargs "${pargs[@]}"
    echo "<!-- rc $rc, ${took}s: $(verdict_of $rc) -->" >>"$out/frame/$name.md"
    log "frame_bench $name: $(verdict_of $rc) (${took}s)"
    case $rc in 0) ;; 124 | 137) timedout=$((timedout + 1)) ;; *) failed=$((failed + 1)) ;; esac
  done
  st=ok
  [ $failed = 0 ] || st="FAILED"
  [ $timedout = 0 ] || st="TIMED OUT"
  [ $notrun = 0 ] || { st=${st#ok}; st="$st${st:+; }NOT RUN: $notrun invocations"; }
  record frame-bench "$st" $((SECONDS - t0)) "$failed failed, $timedout timed out of ${#jobs[@]}"
fi

# --- Summary, archive, returned files.
"$python" "$bundle/gpu_summary.py" "$out" --total $((SECONDS - start)) || log "gpu_summary.py failed"
tar -czf /tmp/gpu-check.tar.gz -C "$(dirname "$out")" "$(basename "$out")"
if [ -n "$ret" ]; then
  mkdir -p "$ret"
  cp "$out/summary.md" "$out/summary.json" /tmp/gpu-check.tar.gz "$ret/"
  [ -f "$out/frame.md" ] && cp "$out/frame.md" "$ret/"
  [ -f "$out/images/images.md" ] && cp "$out/images/images.md" "$ret/"
fi
cat "$out/summary.md"
if grep -q '^overall: ok$' "$out/summary.md"; then exit 0; else exit 1; fi
