#!/usr/bin/env bash
# Start or stop a single-node Slurm cluster on this machine (for tests and local trials).
# Needs root and Debian's slurmctld, slurmd, slurm-client, munge (installed when missing).
#
#   scripts/slurm/local_cluster.sh start STATE_DIR   # writes STATE_DIR/slurm.conf, starts daemons
#   scripts/slurm/local_cluster.sh stop STATE_DIR    # stops them by the PIDs in their pid files
#
# Commands then need SLURM_CONF=STATE_DIR/slurm.conf in their environment.
# OCCGT_SLURM_PORT (default 6817) sets slurmctld's port; slurmd listens on the next one,
# so a second cluster (another STATE_DIR) can run beside the first.
set -euo pipefail
action="${1:?usage: local_cluster.sh start|stop STATE_DIR}"
state="$(mkdir -p "${2:?usage: local_cluster.sh start|stop STATE_DIR}" && cd "$2" && pwd)"

stop_pidfile() {
  local f="$1"
  if [[ -f "$f" ]]; then
    local pid
    pid="$(cat "$f")"
    if [[ -n "$pid" ]] && kill -0 "$pid" 2>/dev/null; then
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2>/dev/null || true
    fi
    rm -f "$f"
  fi
}

case "$action" in
  start)
    [[ $(id -u) == 0 ]] || { echo "local_cluster.sh: needs root" >&2; exit 1; }
    missing=()
    for p in slurmctld slurmd slurm-client munge; do
      dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if ((${#missing[@]})); then
      export DEBIAN_FRONTEND=noninteractive
      # Wait for another apt/dpkg run to finish rather than fail on its lock.
      apt-get -o DPkg::Lock::Timeout=600 update -qq
      apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends \
        "${missing[@]}" </dev/null >/dev/null
    fi
    mem="$(slurmd -C | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p')"
    cpus="$(slurmd -C | sed -n 's/.*CPUs=\([0-9]*\).*/\1/p')"
    port="${OCCGT_SLURM_PORT:-6817}"
    mkdir -p "$state/ctld" "$state/d" "$state/log"
    chown slurm:slurm "$state/ctld" 2>/dev/null || true
    cat >"$state/slurm.conf" <<CONF
ClusterName=occgtlocal
SlurmctldHost=localhost
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/d
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/log/slurmctld.log
SlurmdLogFile=$state/log/slurmd.log
NodeName=localhost CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
    export SLURM_CONF="$state/slurm.conf"
    install -d -o munge -g munge -m 0755 /run/munge
    if [[ ! -S /run/munge/munge.socket.2 ]] || ! munge -n >/dev/null 2>&1; then
      if [[ ! -f /etc/munge/munge.key ]]; then
        /usr/sbin/mungekey --create >/dev/null 2>&1 || dd if=/dev/urandom of=/etc/munge/munge.key bs=1k count=1 2>/dev/null
        chown munge:munge /etc/munge/munge.key; chmod 0400 /etc/munge/munge.key
      fi
      runuser -u munge -- /usr/sbin/munged --pid-file=/run/munge/munged.pid
      cp /run/munge/munged.pid "$state/munged.pid" 2>/dev/null || true
    fi
    /usr/sbin/slurmctld -f "$state/slurm.conf"
    /usr/sbin/slurmd -f "$state/slurm.conf" -N localhost
    for _ in $(seq 100); do
      st="$(sinfo -h -o %T 2>/dev/null || true)"
      if [[ "$st" == idle* ]]; then echo "local_cluster.sh: cluster up (SLURM_CONF=$state/slurm.conf)" >&2; exit 0; fi
      sleep 0.2
    done
    echo "local_cluster.sh: cluster did not become idle; see $state/log" >&2
    tail -n 5 "$state/log/slurmctld.log" "$state/log/slurmd.log" >&2 2>/dev/null || true
    exit 1
    ;;
  stop)
    stop_pidfile "$state/slurmd.pid"
    stop_pidfile "$state/slurmctld.pid"
    stop_pidfile "$state/munged.pid"
    ;;
  *) echo "local_cluster.sh: unknown action '$action' (start|stop)" >&2; exit 2 ;;
esac
