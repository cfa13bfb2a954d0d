#!/usr/bin/env bash
# The Slurm job array of docs/shards.md, run by a real Slurm: starts munged, slurmctld and slurmd
# for one node (this machine, with its own cores and memory) under a temporary directory,
# submits tools/slurm/render.sh (the script the document shows) and the documented merge job
# after it, and compares the merged image with a single render bit for bit. Then an array with
# a failing task: the task is reported with its index and log, the merge job never runs,
# `chambre merge` refuses the bands that are left, and re-running that task alone completes the
# image. Installs slurm-wlm and munge when they are missing (as root, or through sudo). Fails,
# never skips, when Slurm cannot start. Takes about half a minute once installed.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
bin="$root/target/release"
if [ ! -x "$bin/chambre" ]; then
    echo "test_slurm: no $bin/chambre; build it first (cargo build --release --bins)" >&2
    exit 1
fi
# The daemons run as root here (SlurmUser=root), as a one-node test cluster may.
if [ "$(id -u)" -ne 0 ]; then
    exec sudo --preserve-env "$0" "$@"
fi
export PATH="$PATH:/usr/sbin:/sbin"

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
    ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    echo "== installing Slurm (slurm-wlm) and munge"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

# The document must show the very script this test submits.
script=$(cat tools/slurm/render.sh)
if [[ "$(cat docs/shards.md)" != *"$script"* ]]; then
    echo "test_slurm: docs/shards.md does not show tools/slurm/render.sh as it is" >&2
    exit 1
fi

work=$(mktemp -d /tmp/chambre-slurm.XXXXXX)
chmod 755 "$work"
mkdir -p "$work/state" "$work/spool" "$work/log" "$work/ok" "$work/fail"
export SLURM_CONF="$work/slurm.conf"

fail() {
    echo "test_slurm: $*" >&2
    exit 1
}

# Stops the daemons this script started (by the pids they wrote), shows their logs when the
# test failed, and removes the directory.
stop_cluster() {
    local status=$?
    for daemon in slurmd slurmctld munged; do
        local pidfile="$work/$daemon.pid"
        [ -s "$pidfile" ] || continue
        local pid
        pid=$(cat "$pidfile")
        kill "$pid" 2>/dev/null || true
        for _ in $(seq 100); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
    done
    if [ "$status" -ne 0 ]; then
        for log in "$work"/log/*.log; do
            [ -f "$log" ] || continue
            echo "--- $log (last lines)" >&2
            tail -n 25 "$log" >&2
        done
    fi
    rm -rf "$work"
    exit "$status"
}
trap stop_cluster EXIT

# Two free ports, one for slurmctld and one for slurmd (a port that refuses a connection is free).
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
for _ in $(seq 50); do
    ctld_port=$((20000 + RANDOM % 20000))
    port_free "$ctld_port" && port_free $((ctld_port + 1)) && break
done

dd if=/dev/urandom of="$work/munge.key" bs=1024 count=1 status=none
chmod 600 "$work/munge.key"
munged --force --socket="$work/munge.socket" --key-file="$work/munge.key" \
    --pid-file="$work/munged.pid" --log-file="$work/log/munged.log" \
    --seed-file="$work/munged.seed" || fail "munged did not start"

# One node: slurmd's own description of this machine (its name, cores, memory).
node=$(slurmd -C | head -n 1)
[[ "$node" == NodeName=* ]] || fail "slurmd -C did not describe the machine: $node"
cat >"$SLURM_CONF" <<EOF
ClusterName=chambre-test
SlurmctldHost=$(hostname -s)(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$((ctld_port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge.socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=chambre Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld || fail "slurmctld did not start"
slurmd || fail "slurmd did not start"
state=""
for _ in $(seq 60); do
    state=$(sinfo -h -N -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.5
done
[ "$state" = idle ] || fail "the node did not come up within 30 s (state: ${state:-unknown})"
echo "== Slurm up: $node"

# The scene: the sample scene, small and quick.
sed -e 's/^width = .*/width = 96/' -e 's/^height = .*/height = 64/' -e 's/^spp = .*/spp = 4/' \
    scenes/spheres.toml >"$work/scene.toml"
"$bin/chambre" check "$work/scene.toml" | grep -q "96x64 at 4 spp" ||
    fail "the test scene is not the 96x64, 4 spp one"
"$bin/chambre" render "$work/scene.toml" -o "$work/single.pfm" 2>"$work/log/single.log"

# The documented array from `dir`, one core per task here; extra sbatch options after it.
submit_array() {
    local dir=$1
    shift
    (cd "$dir" && SCENE="$work/scene.toml" OUT=out.exr PATH="$bin:$PATH" \
        sbatch --parsable --cpus-per-task=1 "$@" "$root/tools/slurm/render.sh")
}
# The documented merge job, after every task of array `2` succeeded (PFM: raw floats to cmp).
submit_merge() {
    (cd "$1" && PATH="$bin:$PATH" sbatch --parsable --dependency="afterok:$2" \
        --kill-on-invalid-dep=yes --output=merge-%j.log \
        --wrap "chambre merge out.shard-*-of-4.json -o out.pfm")
}
wait_for_jobs() {
    local deadline=$((SECONDS + 90)) jobs
    jobs=$(IFS=,; echo "$*")
    while [ -n "$(squeue -h -j "$jobs" 2>/dev/null)" ]; do
        [ "$SECONDS" -lt "$deadline" ] || {
            squeue >&2
            fail "jobs $jobs still queued or running after 90 s"
        }
        sleep 0.5
    done
}
# `field NAME LINE`: NAME's value in a line of `scontrol show job -o`.
field() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<" $2"; }
# Prints every task of array job `1` that did not complete: its index, state, exit code and
# log. Fails when there is one.
report_failed_tasks() {
    local failed=0 line
    while read -r line; do
        [ "$(field JobState "$line")" = COMPLETED ] && continue
        failed=1
        echo "array task $(field ArrayTaskId "$line") of job $1: $(field JobState "$line"), exit" \
            "code $(field ExitCode "$line"); its log, $(field StdOut "$line"):"
        sed 's/^/    /' "$(field StdOut "$line")" 2>/dev/null || echo "    (no log)"
    done < <(scontrol show job -o "$1")
    return "$failed"
}
# The merge job `2` of directory `1` completed, and its image is the single render's.
check_merged() {
    local merge_state
    merge_state=$(field JobState "$(scontrol show job -o "$2")")
    [ "$merge_state" = COMPLETED ] || {
        cat "$1/merge-$2.log" >&2 || true
        fail "the merge job $2 ended $merge_state"
    }
    cmp "$1/out.pfm" "$work/single.pfm" || fail "the merged image differs from the single render"
}

echo "== the array job and the merge after it"
array=$(submit_array "$work/ok")
merge=$(submit_merge "$work/ok" "$array")
wait_for_jobs "$array" "$merge"
report_failed_tasks "$array" || fail "a task of the array failed"
check_merged "$work/ok" "$merge"
echo "four tasks merged by job $merge: bit-identical to the single render"

echo "== an array with a failing task"
# A stale band of task 2, write-protected: that task refuses to replace it (chambre does so only
# with --force) and fails; the others complete.
touch "$work/fail/out.shard-2-of-4.exr"
chmod 444 "$work/fail/out.shard-2-of-4.exr"
array=$(submit_array "$work/fail")
merge=$(submit_merge "$work/fail" "$array")
wait_for_jobs "$array" "$merge"
if report=$(report_failed_tasks "$array"); then
    fail "the array with a failing task reported none"
fi
echo "$report"
[ "$(grep -c '^array task' <<<"$report")" -eq 1 ] || fail "one task failed, not one reported"
grep -q "^array task 2 of job $array: FAILED, exit code 1:0" <<<"$report" ||
    fail "task 2 is not the one reported"
grep -q "write-protected" <<<"$report" || fail "task 2's log is not shown"
merge_state=$(field JobState "$(scontrol show job -o "$merge")")
[ "$merge_state" = CANCELLED ] || fail "the merge job after a failed task ended $merge_state"
[ ! -e "$work/fail/out.pfm" ] || fail "an incomplete image was merged"
if (cd "$work/fail" && "$bin/chambre" merge out.shard-*-of-4.json -o out.pfm) 2>"$work/log/refused.log"; then
    fail "chambre merge took three of four shards"
fi
grep -q "3 manifests given for a render of 4 shards" "$work/log/refused.log" ||
    fail "chambre merge's refusal: $(cat "$work/log/refused.log")"
echo "the merge job was cancelled ($merge_state) and chambre merge refuses three bands:" \
    "$(cat "$work/log/refused.log")"

echo "== task 2 again, alone, then the merge"
rm -f "$work/fail/out.shard-2-of-4.exr"
array=$(submit_array "$work/fail" --array=2)
merge=$(submit_merge "$work/fail" "$array")
wait_for_jobs "$array" "$merge"
report_failed_tasks "$array" || fail "the re-run task failed"
check_merged "$work/fail" "$merge"
echo "task 2 re-run and merged: bit-identical to the single render"
