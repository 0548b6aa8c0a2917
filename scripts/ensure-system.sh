# Sourced by test.sh from the repository root: the Debian packages the tests need
# (scripts/system-packages.txt, the one list). Missing ones are installed when this machine allows
# it (root and apt-get; quiet, and nothing to do when all are there: one dpkg-query). Otherwise
# it says what is missing; tests that need a missing package then skip with the reason locally,
# and fail under CI=true.
springsim_ensure_system() {
  command -v dpkg-query >/dev/null 2>&1 || return 0   # not Debian or Ubuntu: nothing to check
  local wanted installed missing=() package
  wanted=$(sed -e 's/#.*//' scripts/system-packages.txt | tr -s '[:space:]' ' ')
  # dpkg-query fails when a package is unknown to it; what it prints is still the answer
  installed=" $( (dpkg-query -W -f='${Package} ${db:Status-Abbrev}\n' $wanted 2>/dev/null || true) \
                | awk '$2 == "ii" {printf "%s ", $1}')"
  for package in $wanted; do
    [[ "$installed" == *" $package "* ]] || missing+=("$package")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "test.sh: installing ${missing[*]}" >&2
    if apt-get update -qq >/dev/null 2>&1 && DEBIAN_FRONTEND=noninteractive apt-get install \
        -y -qq --no-install-recommends "${missing[@]}" >/dev/null 2>&1; then
      return 0
    fi
    echo "test.sh: apt-get could not install ${missing[*]}" >&2
  fi
  echo "test.sh: missing system packages: ${missing[*]} (apt-get install ${missing[*]});" \
       "the tests that need them skip here, and fail under CI=true" >&2
}
springsim_ensure_system
