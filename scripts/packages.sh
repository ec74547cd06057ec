# Sourced by setup.sh and web.sh: Debian packages installed when missing.
have_pkg() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

# install_missing LABEL PACKAGE...: apt-get installs the packages given (as
# root or through sudo), after an apt-get update; nothing when none is.
install_missing() {
  local label=$1
  shift
  (($#)) || return 0
  echo "$label: installing $*"
  local sudo=""
  [[ $(id -u) -ne 0 ]] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" >/dev/null
}
