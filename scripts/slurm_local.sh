#!/usr/bin/env bash
# A single-node SLURM cluster on localhost, with accounting, for testing the SLURM profile.
#
#   scripts/slurm_local.sh start    install (apt-get, as root) if missing, configure, start
#   scripts/slurm_local.sh stop     stop every daemon this script started, by process id
#   scripts/slurm_local.sh status   say whether it is up
#   scripts/slurm_local.sh env      print the environment a client needs (SLURM_CONF)
#
# Daemons: munged, mariadbd (the accounting database), slurmdbd, slurmctld and slurmd, all
# run in the foreground under this script's control with their process ids in
# $STEREOVAR_SLURM_DIR/pids (default /tmp/stereovar-slurm). Nothing is written under /etc:
# clients find the cluster through SLURM_CONF=$STEREOVAR_SLURM_DIR/slurm.conf, and the daemons
# listen on loopback ports 16817-16819 (slurmctld, slurmd, slurmdbd) and 16820 (MariaDB),
# so an existing SLURM or database on the machine is left alone. munged serves the standard
# socket /run/munge/munge.socket.2 (the only one SLURM's client commands look for); when
# another munged already serves it, the script stops with exit status 3.
#
# Exit status: 0 on success, 1 when something failed (one line on stderr names it), 3 when
# the cluster cannot be provided on this machine (not root, or no apt-get to install it).
set -euo pipefail

STATE="${STEREOVAR_SLURM_DIR:-/tmp/stereovar-slurm}"
CLUSTER=stereovar
ACCOUNT=stereovar
CTLD_PORT=16817
SLURMD_PORT=16818
DBD_PORT=16819
DB_PORT=16820
PACKAGES=(slurm-wlm slurm-client slurmdbd munge mariadb-server)
# SLURM's client commands only find munged on its compiled-in socket, so ours serves there.
MUNGE_SOCKET=/run/munge/munge.socket.2

say() { echo "slurm_local: $*" >&2; }
die() { say "$*"; exit 1; }
unavailable() { say "$*"; exit 3; }

install_packages() {
    local missing=()
    for exe in slurmctld slurmd slurmdbd sbatch sacct sacctmgr munged mariadbd mariadb-install-db; do
        command -v "$exe" >/dev/null 2>&1 || missing+=("$exe")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    if [ "$(id -u)" -ne 0 ]; then
        unavailable "missing ${missing[*]}; install ${PACKAGES[*]} (needs root) or run as root"
    fi
    command -v apt-get >/dev/null 2>&1 \
        || unavailable "missing ${missing[*]} and no apt-get to install ${PACKAGES[*]}"
    say "installing ${PACKAGES[*]} with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    if ! apt-get install -y -q --no-install-recommends "${PACKAGES[@]}" >"$STATE/apt.log" 2>&1; then
        apt-get update -q >>"$STATE/apt.log" 2>&1 || true
        apt-get install -y -q --no-install-recommends "${PACKAGES[@]}" >>"$STATE/apt.log" 2>&1 \
            || die "apt-get install ${PACKAGES[*]} failed; see $STATE/apt.log"
    fi
}

# Start "$@" in the background, detached, with its output in log/$name.out; remember its pid.
launch() {
    local name=$1
    shift
    setsid "$@" >"$STATE/log/$name.out" 2>&1 </dev/null &
    echo "$name $!" >>"$STATE/pids"
}

wait_for() {  # wait_for SECONDS DESCRIPTION COMMAND...
    local seconds=$1 what=$2
    shift 2
    for _ in $(seq "$((seconds * 4))"); do
        timeout 5 "$@" >/dev/null 2>&1 && return 0
        sleep 0.25
    done
    die "$what did not come up within ${seconds} s; see $STATE/log/"
}

alive() { [ -f "$STATE/pids" ] && while read -r _ pid; do kill -0 "$pid" 2>/dev/null || return 1; done <"$STATE/pids"; }

write_configs() {
    local host mem cpus
    host=$(hostname -s)
    cpus=$(nproc)
    mem=$(awk '/MemTotal/ {print int($2 / 1024)}' /proc/meminfo)
    mem=$((mem > 4096 ? mem - 2048 : mem))
    cat >"$STATE/slurm.conf" <<EOF
ClusterName=$CLUSTER
SlurmctldParameters=enable_configless
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/slurmd
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SwitchType=switch/none
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=10
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=127.0.0.1
AccountingStoragePort=$DBD_PORT
AccountingStoreFlags=job_comment
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
    cat >"$STATE/slurmdbd.conf" <<EOF
AuthType=auth/munge
DbdAddr=127.0.0.1
DbdHost=localhost
DbdPort=$DBD_PORT
SlurmUser=root
PidFile=$STATE/slurmdbd.pid
LogFile=$STATE/log/slurmdbd.log
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=$DB_PORT
StorageUser=slurm
StoragePass=$(cat "$STATE/db.pass")
StorageLoc=slurm_acct_db
EOF
    chmod 600 "$STATE/slurmdbd.conf"
}

start() {
    if alive 2>/dev/null; then
        say "already running (SLURM_CONF=$STATE/slurm.conf)"
        return 0
    fi
    [ -f "$STATE/pids" ] && stop
    mkdir -p "$STATE"
    install_packages
    rm -rf "$STATE/ctld" "$STATE/slurmd" "$STATE/mysql" "$STATE/munge" "$STATE/log"
    mkdir -p "$STATE/ctld" "$STATE/slurmd" "$STATE/munge" "$STATE/log"
    : >"$STATE/pids"
    head -c 24 /dev/urandom | base64 | tr -dc 'A-Za-z0-9' >"$STATE/db.pass"
    write_configs
    export SLURM_CONF="$STATE/slurm.conf"

    # munge: its own key, on the standard socket (refuse to displace a munged we did not start).
    if [ -S "$MUNGE_SOCKET" ] && munge --socket="$MUNGE_SOCKET" -n >/dev/null 2>&1; then
        unavailable "a munged is already serving $MUNGE_SOCKET; stop it or use the cluster it belongs to"
    fi
    mkdir -p "$(dirname "$MUNGE_SOCKET")"
    dd if=/dev/urandom of="$STATE/munge/munge.key" bs=1024 count=1 status=none
    chmod 700 "$STATE/munge"
    chmod 400 "$STATE/munge/munge.key"
    launch munged munged --foreground --force \
        --socket="$MUNGE_SOCKET" --key-file="$STATE/munge/munge.key" \
        --pid-file="$STATE/munge/munged.pid" --seed-file="$STATE/munge/munge.seed" \
        --log-file="$STATE/log/munged.log"
    wait_for 15 munged munge --socket="$MUNGE_SOCKET" -n

    # MariaDB for slurmdbd, on its own data directory and loopback port.
    mariadb-install-db --user=root --datadir="$STATE/mysql" --auth-root-authentication-method=socket \
        --skip-test-db >"$STATE/log/mariadb-install.log" 2>&1 \
        || die "mariadb-install-db failed; see $STATE/log/mariadb-install.log"
    launch mariadbd mariadbd --no-defaults --user=root --datadir="$STATE/mysql" \
        --socket="$STATE/mysql.sock" --bind-address=127.0.0.1 --port="$DB_PORT" \
        --pid-file="$STATE/mariadbd.pid" --innodb-buffer-pool-size=64M \
        --innodb-lock-wait-timeout=900 --log-error="$STATE/log/mariadbd.log"
    wait_for 30 MariaDB mariadb --no-defaults --socket="$STATE/mysql.sock" -e "SELECT 1"
    local pass
    pass=$(cat "$STATE/db.pass")
    mariadb --no-defaults --socket="$STATE/mysql.sock" <<EOF || die "creating the accounting database failed"
CREATE DATABASE IF NOT EXISTS slurm_acct_db;
CREATE USER IF NOT EXISTS 'slurm'@'127.0.0.1' IDENTIFIED BY '$pass';
CREATE USER IF NOT EXISTS 'slurm'@'localhost' IDENTIFIED BY '$pass';
GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';
GRANT ALL ON slurm_acct_db.* TO 'slurm'@'localhost';
FLUSH PRIVILEGES;
EOF

    launch slurmdbd slurmdbd -D  # reads slurmdbd.conf beside $SLURM_CONF
    wait_for 60 slurmdbd sacctmgr -n list cluster
    sacctmgr -i add cluster "$CLUSTER" >/dev/null 2>&1 || true
    sacctmgr -i add account "$ACCOUNT" Cluster="$CLUSTER" Description=stereovar Organization=stereovar \
        >/dev/null 2>&1 || true
    sacctmgr -i add user "$(id -un)" Account="$ACCOUNT" Cluster="$CLUSTER" >/dev/null 2>&1 || true

    launch slurmctld slurmctld -D -i -f "$STATE/slurm.conf"
    wait_for 60 slurmctld scontrol ping
    # Configless slurmd: it fetches slurm.conf from slurmctld and points each job's SLURM_CONF
    # at its cached copy, so srun inside a job finds the cluster.
    launch slurmd slurmd -D --conf-server "127.0.0.1:$CTLD_PORT"
    wait_for 60 "slurmd (node idle)" bash -c "sinfo -h -o '%t' | grep -qx idle"
    say "up: cluster $CLUSTER, account $ACCOUNT, node $(hostname -s); export SLURM_CONF=$SLURM_CONF"
}

stop() {
    [ -f "$STATE/pids" ] || { say "not running"; return 0; }
    # Reverse start order: slurmd, slurmctld, slurmdbd, mariadbd, munged.
    local pids
    pids=$(awk '{a[NR]=$2} END {for (i = NR; i >= 1; i--) print a[i]}' "$STATE/pids")
    for pid in $pids; do
        kill -TERM "$pid" 2>/dev/null || true
        for _ in $(seq 40); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.25
        done
        kill -KILL "$pid" 2>/dev/null || true
    done
    rm -f "$STATE/pids"
    # The configless slurmd caches the fetched slurm.conf in /run/slurm/conf, where every
    # later SLURM client (and so Snakemake's SLURM executor plugin at start-up) would find it
    # and wait about 9 s for this stopped controller: remove the cached copy if it is ours.
    local cached=/run/slurm/conf/slurm.conf
    if [ -f "$cached" ] && grep -qx "ClusterName=$CLUSTER" "$cached" \
        && grep -qx "SlurmctldPort=$CTLD_PORT" "$cached"; then
        rm -rf /run/slurm/conf
    fi
    say "stopped"
}

case "${1:-}" in
start) start ;;
stop) stop ;;
status)
    if alive 2>/dev/null; then
        SLURM_CONF="$STATE/slurm.conf" sinfo
    else
        say "not running"
        exit 1
    fi
    ;;
env) echo "export SLURM_CONF=$STATE/slurm.conf" ;;
*)
    echo "usage: $0 start|stop|status|env" >&2
    exit 2
    ;;
esac
