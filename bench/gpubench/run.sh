#!/usr/bin/env bash
# vkmesh GPU benchmark pack: runs vkmesh_gpubench at 3 cm and 1 cm with this folder's Vulkan loader and the
# machine's GPU driver, and writes gpubench.json and gpubench.txt (everything printed) to the output folder.
#
#   ./run.sh [--out DIR] [--quick] [--icd FILE.json] [--glibc auto|system|bundled] [--timeout S] [BENCH OPTIONS]
#
#   --out DIR     where the results go (default: results/ beside this script, else a new folder in /tmp)
#   --quick       a smoke run for a CPU Vulkan device (lavapipe): 3 frames per voxel size
#   --icd FILE    the Vulkan driver manifest to use (default: found as below)
#   --glibc       auto (default): this machine's glibc when it is new enough for the binary, else glibc/
#   --timeout S   stop the benchmark after S seconds (default 290, so a run ends within 5 minutes; 0: none)
#   anything else goes to vkmesh_gpubench (./vkmesh_gpubench --help lists its options; e.g. --frames 120)
#
# The driver: VK_DRIVER_FILES / VK_ICD_FILENAMES when already set; else an NVIDIA manifest (*nvidia*.json) in
# the usual icd.d folders; else a manifest written to a temporary folder for libGLX_nvidia.so.0 found through
# ldconfig -p or the usual library folders; else (no NVIDIA driver) whatever the loader finds by itself, as
# lavapipe on a machine with Mesa. What it used is printed first.
set -uo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
say() { echo "run.sh: $*"; }

out="" icd="" glibc=auto timeout_s=290 quick=0
bench_args=()
while (($#)); do
  case $1 in
    --out | --icd | --glibc | --timeout)
      if (($# < 2)); then echo "run.sh: $1 needs a value" >&2; exit 2; fi
      case $1 in --out) out=$2 ;; --icd) icd=$2 ;; --glibc) glibc=$2 ;; --timeout) timeout_s=$2 ;; esac
      shift 2 ;;
    --quick) quick=1; shift ;;
    -h | --help) sed -n '2,/^set /p' "${BASH_SOURCE[0]}" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) bench_args+=("$1"); shift ;;
  esac
done
case $glibc in auto | system | bundled) ;; *) echo "run.sh: --glibc takes auto, system or bundled" >&2; exit 2 ;; esac
[[ $timeout_s =~ ^[0-9]+$ ]] || { echo "run.sh: --timeout takes whole seconds" >&2; exit 2; }

# --- the output folder, before anything is printed, so that everything goes into gpubench.txt too ---
if [[ -z $out ]]; then
  out=$here/results
  if ! mkdir -p "$out" 2>/dev/null || [[ ! -w $out ]]; then out=$(mktemp -d /tmp/vkmesh-gpubench.XXXXXX); fi
fi
mkdir -p "$out" || { echo "run.sh: cannot create $out" >&2; exit 2; }
out=$(cd "$out" && pwd)
tmp=$(mktemp -d /tmp/vkmesh-gpubench-icd.XXXXXX)
trap 'rm -rf "$tmp"' EXIT

main() {
  say "pack $here"
  [[ -f $here/BUILD_INFO ]] && sed 's/^/  /' "$here/BUILD_INFO"
  say "machine: $(uname -srm), $(getconf GNU_LIBC_VERSION 2>/dev/null || echo 'glibc version unknown'), $(nproc 2>/dev/null || echo '?') CPUs"

  # --- the NVIDIA driver's library: ldconfig's cache (ldconfig lives in sbin, off a minimal PATH), then folders ---
  local nvidia_lib="" ldconfig d f
  for ldconfig in ldconfig /sbin/ldconfig /usr/sbin/ldconfig; do
    if command -v "$ldconfig" >/dev/null 2>&1; then
      nvidia_lib=$("$ldconfig" -p 2>/dev/null | awk '/libGLX_nvidia\.so\.0 .*x86-64/ { print $NF; exit }')
      break
    fi
  done
  if [[ -z $nvidia_lib ]]; then
    for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu /usr/lib64 /usr/lib \
             /lib/x86_64-linux-gnu /lib64 /usr/lib/x86_64-linux-gnu/nvidia/current /usr/lib/nvidia; do
      if [[ -e $d/libGLX_nvidia.so.0 ]]; then nvidia_lib=$d/libGLX_nvidia.so.0; break; fi
    done
  fi
  [[ -n $nvidia_lib ]] && say "NVIDIA driver library: $nvidia_lib"
  # The pack's lib/ first (its Vulkan loader, and libzstd.so.1 for the binary); the driver's folder too, so that
  # a manifest naming the library without a folder (and the driver's own libraries next to it) resolve even where
  # ldconfig does not know them.
  export LD_LIBRARY_PATH=$here/lib${nvidia_lib:+:$(dirname "$nvidia_lib")}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}

  # --- the driver manifest ---
  local manifest="" how=""
  if [[ -n $icd ]]; then
    [[ -f $icd ]] || { say "error: --icd $icd: no such file"; return 2; }
    manifest=$(cd "$(dirname "$icd")" && pwd)/$(basename "$icd") how="given with --icd"
  elif [[ -n ${VK_DRIVER_FILES:-} || -n ${VK_ICD_FILENAMES:-} ]]; then
    how="from the environment: VK_DRIVER_FILES=${VK_DRIVER_FILES:-} VK_ICD_FILENAMES=${VK_ICD_FILENAMES:-}"
  else
    local dirs=(/etc/vulkan/icd.d /usr/share/vulkan/icd.d /usr/local/share/vulkan/icd.d /usr/local/etc/vulkan/icd.d
                /etc/xdg/vulkan/icd.d /usr/local/nvidia/share/vulkan/icd.d /usr/local/nvidia/etc/vulkan/icd.d)
    local IFS=:
    for d in ${XDG_CONFIG_DIRS:-} ${XDG_DATA_DIRS:-}; do dirs+=("$d/vulkan/icd.d"); done
    unset IFS
    for d in "${dirs[@]}"; do
      for f in "$d"/*nvidia*.json; do
        if [[ -f $f ]]; then manifest=$f how="found in $d"; break 2; fi
      done
    done
    if [[ -z $manifest && -n $nvidia_lib ]]; then
      manifest=$tmp/nvidia_icd.json how="written for $nvidia_lib (no NVIDIA manifest installed)"
      printf '{\n  "file_format_version": "1.0.0",\n  "ICD": { "library_path": "%s", "api_version": "1.3.0" }\n}\n' \
        "$nvidia_lib" >"$manifest"
    fi
    if [[ -z $manifest ]]; then
      how="no NVIDIA driver found: the Vulkan loader searches its standard folders"
      local seen=()
      for d in "${dirs[@]}" "${HOME:-/nonexistent}/.local/share/vulkan/icd.d"; do
        for f in "$d"/*.json; do [[ -f $f ]] && seen+=("$f"); done
      done
      how+=" (manifests there: ${seen[*]:-none})"
    fi
  fi
  if [[ -n $manifest ]]; then
    export VK_DRIVER_FILES=$manifest VK_ICD_FILENAMES=$manifest   # the first for loaders >= 1.3.207, the second before
    say "Vulkan driver manifest: $manifest ($how)"
    sed 's/^/  /' "$manifest"
  else
    say "Vulkan driver: $how"
  fi
  say "Vulkan loader: $here/lib/libvulkan.so.1 (LD_LIBRARY_PATH=$LD_LIBRARY_PATH)"
  if [[ -r /proc/driver/nvidia/version ]]; then say "$(head -n1 /proc/driver/nvidia/version)"; fi
  local smi
  for smi in nvidia-smi /usr/bin/nvidia-smi /usr/local/nvidia/bin/nvidia-smi; do
    if command -v "$smi" >/dev/null 2>&1; then
      say "nvidia-smi: $("$smi" --query-gpu=name,driver_version,clocks.max.sm,memory.total --format=csv,noheader 2>&1 | head -n4 | tr '\n' ';')"
      break
    fi
  done

  # --- glibc: the machine's when the binary's symbol versions are there, else the pack's ---
  local run=("$here/vkmesh_gpubench") probe
  if [[ $glibc != system ]]; then
    if [[ $glibc == bundled ]] || ! probe=$("$here/vkmesh_gpubench" --help 2>&1 >/dev/null); then
      if [[ $glibc == auto ]]; then
        if [[ $probe != *GLIBC* ]]; then say "error: vkmesh_gpubench does not start: $probe"; return 2; fi
        say "this machine's glibc is too old for the binary ($probe); using the pack's glibc/"
      fi
      run=("$here/glibc/ld-linux-x86-64.so.2" --library-path "$here/glibc:$LD_LIBRARY_PATH" "$here/vkmesh_gpubench")
      say "glibc: the pack's ($here/glibc)"
    fi
  fi

  # --- the benchmark: defaults sized for a datacenter GPU (the whole run well under 5 minutes there) ---
  local args=(--json "$out/gpubench.json")
  if ((quick)); then
    args+=(--quick)
  else
    has() { local a; for a in "${bench_args[@]}"; do [[ $a == "$1" || $a == "$1="* ]] && return 0; done; return 1; }
    has --voxel || args+=(--voxel "0.03,0.01")
    has --frames || args+=(--frames 60)       # vkmesh synth's default sequence, one lap of the room
    has --repeat || args+=(--repeat 5)        # 300 timed frames per voxel size, each run into a fresh volume
    has --warmup || args+=(--warmup 30)
    # Each pass's GPU time too: one run on a GPU says which passes cost what there (every pass is already
    # followed by a full barrier, so a timestamp after it adds little on a GPU).
    has --pass-times || args+=(--pass-times)
  fi
  args+=("${bench_args[@]}")
  if ((timeout_s > 0)) && command -v timeout >/dev/null 2>&1; then run=(timeout -k 10 "$timeout_s" "${run[@]}"); fi
  say "running: ${run[*]} ${args[*]}"
  local start=$SECONDS status=0
  "${run[@]}" "${args[@]}" || status=$?
  if ((status == 124 || status == 137)); then say "error: the benchmark ran past --timeout $timeout_s s and was stopped"; fi
  if ((status == 0)); then
    say "done in $((SECONDS - start)) s; results in $out (gpubench.json, gpubench.txt)"
  else
    say "FAILED with exit code $status after $((SECONDS - start)) s; what it printed is in $out/gpubench.txt"
  fi
  return "$status"
}

main 2>&1 | tee "$out/gpubench.txt"
exit "${PIPESTATUS[0]}"
