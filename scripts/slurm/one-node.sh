#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for the tests of the cluster
# scripts (docs/cluster.md): `up` installs Debian's slurm-wlm and munge if
# missing, writes /etc/slurm/slurm.conf, starts munged (as the munge user),
# slurmctld and slurmd without systemd, and waits until the node is idle;
# `down` stops the three daemons by their process ids. Both are idempotent.
# Runs as root. No cgroup.conf is written: slurmd starts without one.
set -euo pipefail

usage() {
    cat >&2 <<'USAGE'
usage: scripts/slurm/one-node.sh up|down|status

  up      install slurm-wlm and munge if missing, start munged, slurmctld
          and slurmd, wait (at most $SLURM_UP_TIMEOUT seconds, default 60)
          until the node is idle
  down    stop slurmd, slurmctld and munged by their process ids
  status  print the node's state (sinfo)
USAGE
    exit 2
}

die() {
    echo "one-node.sh: $*" >&2
    exit 1
}

conf=/etc/slurm/slurm.conf
marker="# Written by komplex scripts/slurm/one-node.sh"
ctld_pid=/run/slurmctld.pid
slurmd_pid=/run/slurmd.pid
munge_pid=/run/munge/munged.pid
logs=/var/log/slurm
host=$(hostname -s)

# The process id in pid file $1 if that process is alive, else nothing.
live_pid() {
    local pid
    [ -r "$1" ] || return 1
    pid=$(cat "$1" 2>/dev/null) || return 1
    [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null && echo "$pid"
}

# Stops the daemons whose names and pid files are given in pairs: TERM to
# all at once (each takes a second or two to exit), then KILL to any still
# alive after 10 s.
stop() {
    local names=() pids=() files=() pid i
    while [ $# -gt 0 ]; do
        if pid=$(live_pid "$2"); then
            kill -TERM "$pid" 2>/dev/null || true
            names+=("$1") pids+=("$pid") files+=("$2")
        else
            echo "$1: not running"
        fi
        shift 2
    done
    for i in "${!pids[@]}"; do
        for _ in $(seq 1 100); do
            kill -0 "${pids[$i]}" 2>/dev/null || break
            sleep 0.1
        done
        if kill -0 "${pids[$i]}" 2>/dev/null; then
            echo "${names[$i]}: pid ${pids[$i]} still alive after 10 s, sending KILL" >&2
            kill -KILL "${pids[$i]}" 2>/dev/null || true
        fi
        rm -f "${files[$i]}"
        echo "${names[$i]}: stopped (pid ${pids[$i]})"
    done
}

install_packages() {
    if command -v slurmctld >/dev/null && command -v slurmd >/dev/null \
        && command -v sbatch >/dev/null && command -v munged >/dev/null; then
        return 0
    fi
    command -v apt-get >/dev/null || die "slurm-wlm and munge are missing and there is no apt-get to install them"
    echo "installing slurm-wlm and munge (Debian packages)"
    apt-get update -qq || die "apt-get update failed"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null \
        || die "apt-get install slurm-wlm munge failed"
}

start_munge() {
    if live_pid "$munge_pid" >/dev/null; then
        return 0
    fi
    if [ ! -s /etc/munge/munge.key ]; then
        runuser -u munge -- mungekey --create || die "cannot create /etc/munge/munge.key"
    fi
    install -d -o munge -g munge -m 0755 /run/munge
    install -d -o munge -g munge -m 0700 /var/log/munge /var/lib/munge
    runuser -u munge -- /usr/sbin/munged || die "munged did not start (see /var/log/munge/munged.log)"
    munge -n | unmunge >/dev/null || die "munge does not round-trip a credential (see /var/log/munge/munged.log)"
}

write_conf() {
    if [ -e "$conf" ] && ! grep -qF "$marker" "$conf"; then
        die "$conf exists and was not written by this script; not replacing it"
    fi
    # The node line as slurmd reads this machine (CPUs, sockets, cores, memory).
    local node
    node=$(slurmd -C | head -n 1)
    case "$node" in
        NodeName=*) ;;
        *) die "slurmd -C did not describe this node: $node" ;;
    esac
    install -d -m 0755 /etc/slurm /var/spool/slurmctld /var/spool/slurmd "$logs"
    cat >"$conf.tmp" <<CONF
$marker (a one-node test cluster; docs/cluster.md)
ClusterName=komplex
SlurmctldHost=$host
SlurmUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=$ctld_pid
SlurmdPidFile=$slurmd_pid
SlurmctldLogFile=$logs/slurmctld.log
SlurmdLogFile=$logs/slurmd.log
$node State=UNKNOWN
PartitionName=main Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
    mv "$conf.tmp" "$conf"
}

node_state() {
    sinfo -h -r -n "$host" -o %T 2>/dev/null | head -n 1
}

up() {
    [ "$(id -u)" -eq 0 ] || die "must run as root (it installs packages and starts daemons); run it with sudo"
    install_packages
    start_munge
    if ! live_pid "$ctld_pid" >/dev/null || ! live_pid "$slurmd_pid" >/dev/null; then
        write_conf
    fi
    if ! live_pid "$ctld_pid" >/dev/null; then
        # -c: start with an empty queue (a test cluster keeps no jobs across down and up).
        slurmctld -c || die "slurmctld did not start (see $logs/slurmctld.log)"
    fi
    if ! live_pid "$slurmd_pid" >/dev/null; then
        slurmd || die "slurmd did not start (see $logs/slurmd.log)"
    fi
    local timeout=${SLURM_UP_TIMEOUT:-60} state=""
    local deadline=$((SECONDS + timeout))
    while [ "$SECONDS" -lt "$deadline" ]; do
        state=$(node_state)
        case "$state" in
            idle | mixed | allocated) echo "slurm: node $host is $state"; return 0 ;;
        esac
        sleep 0.5
    done
    {
        echo "one-node.sh: node $host not idle after $timeout s (state: '${state:-no answer from slurmctld}')"
        for f in "$logs/slurmctld.log" "$logs/slurmd.log"; do
            echo "--- last lines of $f"
            tail -n 20 "$f" 2>/dev/null || true
        done
    } >&2
    exit 1
}

down() {
    stop slurmd "$slurmd_pid" slurmctld "$ctld_pid" munged "$munge_pid"
}

[ $# -eq 1 ] || usage
case "$1" in
    up) up ;;
    down) down ;;
    status) sinfo ;;
    *) usage ;;
esac
