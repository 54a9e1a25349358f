# Sourced by the side-by-side benchmarks: installs the Debian package liggghts (with mpirun and
# GNU time, which the scripts use) when it is missing.
if ! command -v liggghts >/dev/null 2>&1; then
  echo "installing the Debian package liggghts"
  sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get install -y -q liggghts openmpi-bin time >/dev/null
fi
