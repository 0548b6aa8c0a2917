# Sourced by test.sh from the repository root: the Debian packages the tests need
# (scripts/system-packages.txt, the one list: the lines above its [external] line for every tier,
# the lines below it too when SYSTEM_TIERS holds "external"). Missing ones are installed when this
# machine allows it (root and apt-get; quiet, and nothing to do when all are there: one
# dpkg-query). Otherwise
# it says what is missing; tests that need a missing package then skip with the reason locally,
# and fail under CI=true.
springsim_ensure_system() {
  command -v dpkg-query >/dev/null 2>&1 || return 0   # not Debian or Ubuntu: nothing to check
  local wanted installed missing=() package
  local keep='/^\[external\]/d'   # every line but the section mark
  [[ "${SYSTEM_TIERS:-default}" == *external* ]] || keep='/^\[external\]/,$d'
  wanted=$(sed -e "$keep" -e 's/#.*//' scripts/system-packages.txt | tr -s '[:space:]' ' ')
  # dpkg-query fails when a package is unknown to it; what it prints is still the answer
  installed=" $( (dpkg-query -W -f='${Package} ${db:Status-Abbrev}\n' $wanted 2>/dev/null || true) \
                | awk '$2 == "ii" {printf "%s ", $1}')"
  for package in $wanted; do
    [[ "$installed" == *" $package "* ]] || missing+=("$package")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    # setup_stage (scripts/ensure-venv.sh, sourced first) says what it does and ticks while it runs
    if setup_stage updating "updating apt's package lists to install ${missing[*]}" \
          apt-get update -qq \
        && DEBIAN_FRONTEND=noninteractive setup_stage installing \
          "installing the system packages the tests need: ${missing[*]}" \
          apt-get install -y -qq --no-install-recommends "${missing[@]}"; then
      return 0
    fi
    echo "test.sh: apt-get could not install ${missing[*]}" >&2
  fi
  echo "test.sh: missing system packages: ${missing[*]} (apt-get install ${missing[*]});" \
       "the tests that need them skip here, and fail under CI=true" >&2
}
springsim_ensure_system
