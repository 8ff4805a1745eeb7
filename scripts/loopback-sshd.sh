# Sourced by scripts/demo.sh: a throw-away OpenSSH server on 127.0.0.1 whose remote commands
# find the emulated router's tools (wl, nexutil, makecsiparams) first in PATH.
# start_loopback_sshd DIR TOOLS_DIR  -> SSHD_PORT, SSHD_KEY, SSHD_KNOWN_HOSTS, SSHD_PID
start_loopback_sshd() {
  local dir=$1 tools=$2
  mkdir -p "$dir"; chmod 700 "$dir"
  ssh-keygen -q -t ed25519 -N "" -f "$dir/host_key"
  ssh-keygen -q -t ed25519 -N "" -f "$dir/client_key"
  cp "$dir/client_key.pub" "$dir/authorized_keys"
  SSHD_PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
  cat >"$dir/sshd_config" <<CFG
ListenAddress 127.0.0.1
Port $SSHD_PORT
HostKey $dir/host_key
AuthorizedKeysFile $dir/authorized_keys
PidFile $dir/sshd.pid
StrictModes no
UsePAM no
PasswordAuthentication no
KbdInteractiveAuthentication no
PermitRootLogin prohibit-password
SetEnv PATH=$tools:/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin
LogLevel ERROR
CFG
  echo "[127.0.0.1]:$SSHD_PORT $(cut -d' ' -f1,2 "$dir/host_key.pub")" >"$dir/known_hosts"
  mkdir -p /run/sshd 2>/dev/null || true
  /usr/sbin/sshd -D -e -f "$dir/sshd_config" 2>"$dir/sshd.log" &
  SSHD_PID=$!
  SSHD_KEY=$dir/client_key
  SSHD_KNOWN_HOSTS=$dir/known_hosts
  for _ in $(seq 50); do (exec 3<>"/dev/tcp/127.0.0.1/$SSHD_PORT") 2>/dev/null && return 0; sleep 0.1; done
  echo "loopback sshd did not start (see $dir/sshd.log)" >&2; return 1
}
