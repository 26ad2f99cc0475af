#!/bin/bash
# A one-node SLURM cluster on this Debian machine, for trying
# repose-workers.sbatch (and for CI) without a real cluster.
#
#   sudo deploy/slurm/local-cluster.sh          # install, configure, start
#   sudo deploy/slurm/local-cluster.sh status   # daemons and node state
#   sudo deploy/slurm/local-cluster.sh stop     # stop slurmd, slurmctld, munged
#
# "start" (the default) installs slurm-wlm and munge with apt-get when they are
# missing, creates a munge key if there is none, writes a minimal slurm.conf
# for a single node named after `hostname -s` with the CPUs and memory that
# slurmd detects here, starts munged, slurmctld and slurmd directly (no
# systemd needed) and waits until the node is idle. Daemons already running
# are left alone, so running it again is harmless. If the configuration it
# would write differs from the one in place, the slurm daemons are restarted.
#
# It only ever overwrites a slurm.conf that it wrote itself (recognised by its
# first line); set LOCAL_SLURM_FORCE=1 to replace another one.
#
# No cgroups are used (proctrack/linuxproc, task/none), so jobs are neither
# confined to their cores nor limited in memory: fine for a test machine, not
# for a shared one. Jobs run as the submitting user; root may submit.
#
# Settings (environment):
#   LOCAL_SLURM_TIMEOUT   seconds to wait for the node to become idle (60)
#   LOCAL_SLURM_PARTITION partition name (debug)
#   LOCAL_SLURM_FORCE     1 to overwrite a slurm.conf not written by this script
set -euo pipefail

CONF_DIR=/etc/slurm
CONF=$CONF_DIR/slurm.conf
MARKER="# Written by deploy/slurm/local-cluster.sh (one-node test cluster)"
TIMEOUT=${LOCAL_SLURM_TIMEOUT:-60}
PARTITION=${LOCAL_SLURM_PARTITION:-debug}
CTLD_PID=/run/slurmctld.pid
SLURMD_PID=/run/slurmd.pid
MUNGE_PID=/run/munge/munged.pid
LOG_DIR=/var/log/slurm
MUNGE_KEY=/etc/munge/munge.key

die() {
  echo "local-cluster: error: $*" >&2
  exit 1
}
say() { echo "local-cluster: $*"; }

# pid from a pid file if that process is alive and is the named program
alive_pid() { # pidfile program
  local pid
  [[ -r $1 ]] || return 1
  pid=$(tr -dc '0-9' <"$1")
  [[ -n $pid ]] && kill -0 "$pid" 2>/dev/null || return 1
  [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$2"* ]] || return 1
  echo "$pid"
}

# wait up to 10 s for a daemon that forked into the background to write its
# pid file
wait_alive() { # pidfile program
  local i
  for ((i = 0; i < 100; i++)); do
    alive_pid "$1" "$2" >/dev/null && return 0
    sleep 0.1
  done
  return 1
}

show_logs() {
  local f
  for f in "$LOG_DIR/slurmctld.log" "$LOG_DIR/slurmd.log"; do
    [[ -r $f ]] || continue
    echo "---- last lines of $f" >&2
    tail -n 15 "$f" >&2
  done
}

install_packages() {
  local missing=() pkg
  for pkg in slurm-wlm munge; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q 'ok installed' ||
      missing+=("$pkg")
  done
  ((${#missing[@]})) || return 0
  command -v apt-get >/dev/null || die "apt-get not found: this script is for Debian/Ubuntu"
  say "installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  local log
  log=$(mktemp)
  # The package lists may be absent or stale (fresh containers): update once
  # and retry if the first attempt fails.
  if ! apt-get install -y -qq --no-install-recommends "${missing[@]}" >"$log" 2>&1; then
    if ! { apt-get update -qq &&
      apt-get install -y -qq --no-install-recommends "${missing[@]}"; } >"$log" 2>&1; then
      tail -n 20 "$log" >&2
      rm -f "$log"
      die "apt-get install ${missing[*]} failed"
    fi
  fi
  rm -f "$log"
}

start_munge() {
  if [[ ! -s $MUNGE_KEY ]]; then
    say "creating $MUNGE_KEY"
    install -d -o munge -g munge -m 0700 /etc/munge
    if command -v mungekey >/dev/null; then
      runuser -u munge -- mungekey --create --keyfile="$MUNGE_KEY"
    else
      dd if=/dev/urandom bs=1 count=1024 of="$MUNGE_KEY" status=none
    fi
    chown munge:munge "$MUNGE_KEY"
    chmod 0400 "$MUNGE_KEY"
  fi
  if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    return 0
  fi
  say "starting munged"
  install -d -o munge -g munge -m 0755 /run/munge
  install -d -o munge -g munge -m 0700 /var/log/munge /var/lib/munge
  runuser -u munge -- /usr/sbin/munged || die "munged did not start (see /var/log/munge/munged.log)"
  local i
  for ((i = 0; i < 50; i++)); do
    munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  die "munged is not answering (see /var/log/munge/munged.log)"
}

# The slurm.conf for this machine, on stdout.
render_conf() {
  local node hw mem
  node=$(hostname -s)
  [[ -n $node ]] || die "hostname -s is empty"
  # slurmd -C prints the hardware slurmd itself will report when it registers
  # (CPUs, sockets, cores, threads, RealMemory). A node configured with more
  # than that is drained, so copy its figures; fall back to nproc and
  # /proc/meminfo if it prints nothing usable.
  hw=$(slurmd -C 2>/dev/null | sed -n '1s/^NodeName=[^ ]* //p' || true)
  if [[ ! $hw =~ CPUs=[0-9]+ || ! $hw =~ RealMemory=[0-9]+ ]]; then
    mem=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 }' /proc/meminfo)
    [[ -n $mem && $mem -gt 0 ]] || mem=1024
    hw="CPUs=$(nproc) RealMemory=$mem"
  fi
  cat <<EOF
$MARKER
ClusterName=local
SlurmctldHost=$node(127.0.0.1)
AuthType=auth/munge
CredType=cred/munge
SlurmUser=slurm
SlurmdUser=root
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=$CTLD_PID
SlurmdPidFile=$SLURMD_PID
SlurmctldLogFile=$LOG_DIR/slurmctld.log
SlurmdLogFile=$LOG_DIR/slurmd.log
# no cgroups, no systemd: track processes through /proc, no task binding
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
# reject jobs that can never run here (e.g. more cores than the node has)
# at submission, instead of leaving them pending forever
EnforcePartLimits=ALL
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# a node that was down (daemon restart) comes back by itself
ReturnToService=2
SlurmdTimeout=60
MailProg=/bin/true
NodeName=$node NodeAddr=127.0.0.1 $hw State=UNKNOWN
PartitionName=$PARTITION Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
}

stop_daemon() { # pidfile program
  local pid i
  pid=$(alive_pid "$1" "$2") || return 0
  say "stopping $2 (pid $pid)"
  kill -TERM "$pid" 2>/dev/null || true
  for ((i = 0; i < 100; i++)); do
    kill -0 "$pid" 2>/dev/null || return 0
    sleep 0.1
  done
  say "$2 ignored SIGTERM for 10 s; killing it"
  kill -KILL "$pid" 2>/dev/null || true
}

node_state() {
  sinfo -h -N -n "$(hostname -s)" -o %T 2>/dev/null | head -n 1
}

# true once slurmd has registered with slurmctld at or after epoch second $1
registered_since() {
  local started
  (($1 == 0)) && return 0
  started=$(scontrol -o show node "$(hostname -s)" 2>/dev/null |
    sed -n 's/.*SlurmdStartTime=\([^ ]*\).*/\1/p')
  [[ -n $started && $started != None ]] || return 1
  started=$(date -d "$started" +%s 2>/dev/null) || return 1
  ((started >= $1))
}

do_start() {
  [[ $(id -u) -eq 0 ]] || die "run as root (it installs packages and starts system daemons)"
  install_packages
  id slurm >/dev/null 2>&1 || die "user 'slurm' is missing (normally created by the slurm packages)"
  start_munge

  local new restart=0
  new=$(render_conf)
  if [[ -e $CONF ]] && ! cmp -s <(printf '%s\n' "$new") "$CONF"; then
    if [[ $(head -n 1 "$CONF") != "$MARKER" && ${LOCAL_SLURM_FORCE:-0} != 1 ]]; then
      die "$CONF exists and was not written by this script; set LOCAL_SLURM_FORCE=1 to replace it"
    fi
    restart=1
  fi
  if [[ ! -e $CONF || $restart == 1 ]]; then
    say "writing $CONF"
    install -d -m 0755 "$CONF_DIR"
    printf '%s\n' "$new" >"$CONF"
    chmod 0644 "$CONF"
  fi
  if ((restart)); then
    say "configuration changed: restarting the slurm daemons"
    stop_daemon "$SLURMD_PID" slurmd
    stop_daemon "$CTLD_PID" slurmctld
  fi

  install -d -o slurm -g slurm -m 0755 /var/spool/slurmctld "$LOG_DIR"
  install -d -m 0755 /var/spool/slurmd

  local t0=$SECONDS since=0
  if alive_pid "$CTLD_PID" slurmctld >/dev/null; then
    say "slurmctld already running"
  else
    say "starting slurmctld"
    /usr/sbin/slurmctld && wait_alive "$CTLD_PID" slurmctld ||
      { show_logs; die "slurmctld did not start"; }
  fi
  if alive_pid "$SLURMD_PID" slurmd >/dev/null; then
    say "slurmd already running"
  else
    say "starting slurmd"
    since=$(date +%s)
    /usr/sbin/slurmd && wait_alive "$SLURMD_PID" slurmd ||
      { show_logs; die "slurmd did not start"; }
  fi

  local state=""
  while ((SECONDS - t0 < TIMEOUT)); do
    state=$(node_state || true)
    # a restarted slurmctld reports the node's saved state at once; wait
    # until the slurmd just started has registered
    registered_since "$since" || state="waiting for slurmd"
    case $state in
      idle | mixed | allocated | completing)
        say "node $(hostname -s) is $state after $((SECONDS - t0)) s; partition '$PARTITION' is ready"
        return 0
        ;;
    esac
    alive_pid "$CTLD_PID" slurmctld >/dev/null || { show_logs; die "slurmctld exited"; }
    alive_pid "$SLURMD_PID" slurmd >/dev/null || { show_logs; die "slurmd exited"; }
    sleep 1
  done
  show_logs
  sinfo -N -l >&2 2>/dev/null || true
  die "node $(hostname -s) not idle after $TIMEOUT s (state: '${state:-unknown}')"
}

do_stop() {
  [[ $(id -u) -eq 0 ]] || die "run as root"
  stop_daemon "$SLURMD_PID" slurmd
  stop_daemon "$CTLD_PID" slurmctld
  stop_daemon "$MUNGE_PID" munged
  say "stopped"
}

do_status() {
  local name pidfile pid
  for name in munged:$MUNGE_PID slurmctld:$CTLD_PID slurmd:$SLURMD_PID; do
    pidfile=${name#*:}
    name=${name%%:*}
    if pid=$(alive_pid "$pidfile" "$name"); then
      echo "$name: running (pid $pid)"
    else
      echo "$name: not running"
    fi
  done
  if alive_pid "$CTLD_PID" slurmctld >/dev/null; then
    sinfo -N -l
  fi
}

case ${1:-start} in
  start) do_start ;;
  stop) do_stop ;;
  status) do_status ;;
  *)
    echo "usage: $0 [start|stop|status]" >&2
    exit 2
    ;;
esac
