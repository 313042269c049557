#!/usr/bin/env bash
# Checks a firmware image: no heap, no exception or RTTI machinery; prints flash/RAM use and the
# largest stack frames (-fstack-usage). Usage: check_image.sh IMAGE.elf [STACK_USAGE_DIR]
set -euo pipefail
elf=$1
su_dir=${2:-}
forbidden='^(malloc|free|realloc|calloc|_sbrk|_sbrk_r|_malloc_r|_free_r|_calloc_r|_realloc_r|__cxa_throw|__cxa_allocate_exception|__cxa_begin_catch|__gxx_personality_v0|_Unwind_Resume|_Unwind_RaiseException|__cxa_pure_virtual|_ZTI.*|_ZTS.*)$'
hits=$(arm-none-eabi-nm --defined-only "$elf" | awk '{print $3}' | grep -E "$forbidden" || true)
undef=$(arm-none-eabi-nm --undefined-only "$elf" | awk '{print $2}' | grep -E "$forbidden" || true)
if [ -n "$hits$undef" ]; then
  echo "FAIL: $elf contains forbidden symbols:"
  echo "$hits $undef"
  exit 1
fi
echo "no heap, exception or RTTI symbols in $(basename "$elf")"
read -r text data _ < <(arm-none-eabi-size "$elf" | tail -1)
# RAM by section (size's "bss" column sums every NOBITS section, the main stack and .noinit too).
section() { arm-none-eabi-size -A "$elf" | awk -v s="$1" '$1==s{n=$2} END{print n+0}'; }
bss=$(section .bss)
noinit=$(section .noinit)
top=$(arm-none-eabi-nm "$elf" | awk '$3=="__stack_top__"{print $1}')
limit=$(arm-none-eabi-nm "$elf" | awk '$3=="__stack_limit__"{print $1}')
stack=$((16#$top - 16#$limit))
echo "flash (text+data): $((text + data)) bytes; RAM: data $data + bss $bss + noinit $noinit + main stack $stack = $((data + bss + noinit + stack)) bytes"
if [ -n "$su_dir" ] && [ -d "$su_dir" ]; then
  echo "largest stack frames (-fstack-usage):"
  find "$su_dir" -name '*.su' -exec cat {} + | sort -t$'\t' -k2 -n -r | sed -n '1,8s/^/  /p'
fi
