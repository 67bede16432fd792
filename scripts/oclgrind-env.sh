# Sourced by scripts/oclgrind-check.sh and scripts/cross-impl.sh: registers Oclgrind for this
# script's runs only. Finds its ICD library, creates $work (removed on exit) and points
# OCL_ICD_VENDORS at $work/vendors: the system's .icd files plus one for Oclgrind
# (/etc/OpenCL/vendors is not touched). Without Oclgrind: exit 77 (ctest: skipped), or 1 under CI=true.
# usage: oclgrind_register NAME   (NAME prefixes the messages)
oclgrind_register() {
  local name="$1" f
  icd_lib=""
  for f in "${OCLGRIND_ICD_LIB:-}" /usr/lib/oclgrind/liboclgrind-rt-icd.so \
           /usr/lib/x86_64-linux-gnu/oclgrind/liboclgrind-rt-icd.so /usr/local/lib/liboclgrind-rt-icd.so; do
    if [ -n "$f" ] && [ -f "$f" ]; then icd_lib="$f"; break; fi
  done
  if [ -z "$icd_lib" ]; then
    local msg="$name: Oclgrind is not installed (Debian: oclgrind, scripts/install-deps.sh)"
    if [ "${CI:-}" = "true" ]; then echo "$msg" >&2; exit 1; fi
    echo "SKIPPED: $msg"
    exit 77
  fi
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
  mkdir -p "$work/vendors"
  cp /etc/OpenCL/vendors/*.icd "$work/vendors/" 2>/dev/null || true
  echo "$icd_lib" >"$work/vendors/oclgrind.icd"
  export OCL_ICD_VENDORS="$work/vendors"
}
