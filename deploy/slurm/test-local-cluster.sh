#!/usr/bin/env bash
# The Slurm deployment on a real Slurm: installs Debian's slurm-wlm and munge if missing,
# starts munged, slurmctld and slurmd as a one-node cluster on localhost (every file in a
# temporary folder: key, sockets, configuration, state, logs), submits deploy/slurm/submit.sh's
# array of 4 shards × 2 passes and its merge job, and checks the merged image against one
# run of the same 8 passes on this machine (1e-6 per pixel and channel: tests/progressive.rs's
# tolerance). Then the resume story of docs/scale-out.md: with one shard's film gone the merge
# job fails naming its passes; rerunning that array index writes the same film, byte for
# byte, and the merge then passes. Stops what it started by process id on any exit. If Slurm
# cannot start here it says why and fails.
#
#   deploy/slurm/test-local-cluster.sh      (as root; about 30 s on 2 cores once built)
#
# KEEP=1 keeps the temporary folder. DPM_SLURM_TIMEOUT bounds each wait for jobs (seconds).
set -euo pipefail
cd "$(dirname "$0")/../.."
repo=$(pwd)
started=$SECONDS
timeout=${DPM_SLURM_TIMEOUT:-240}

fail() {
  echo "test-local-cluster.sh: FAIL: $*" >&2
  exit 1
}
[ "$(id -u)" -eq 0 ] || fail "needs root: it installs packages and runs slurmd as SlurmUser=root"

missing=
for tool in slurmctld slurmd sbatch scontrol sinfo scancel munged mungekey; do
  command -v "$tool" >/dev/null || missing+=" $tool"
done
if [ -n "$missing" ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update
  # Debian's packages try to start the daemons through init and are refused without one;
  # this script starts its own.
  apt-get install -y slurm-wlm munge
fi

# dpm and the image comparison, built as CI builds them.
cargo build --release --bin dpm --example compare_images
target=$(realpath "${CARGO_TARGET_DIR:-target}")
dpm=$target/release/dpm
compare=$target/release/examples/compare_images

tmp=$(mktemp -d /tmp/dpm-slurm.XXXXXX)
# munged refuses a socket in a folder others cannot enter; its key folder stays private.
chmod 755 "$tmp"
mkdir -p "$tmp"/{run,state,spool,log,films}
mkdir -m 700 "$tmp/key"

pids=()
cleanup() {
  local status=$?
  trap - EXIT
  set +e
  if [ -n "${SLURM_CONF:-}" ] && [ "${#pids[@]}" -gt 1 ]; then
    # Job steps outlive slurmd by design: cancel this cluster's jobs before stopping it.
    scancel --quiet --user=root 2>/dev/null
    sleep 1
  fi
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill "${pids[i]}" 2>/dev/null
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    kill -9 "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  if [ "$status" -ne 0 ]; then
    for f in "$tmp"/log/*; do
      [ -f "$f" ] && { echo "---- ${f#"$tmp"/} (last lines)"; tail -n 25 "$f"; }
    done >&2
  fi
  if [ -n "${KEEP:-}" ]; then echo "kept $tmp" >&2; else rm -rf "$tmp"; fi
  exit "$status"
}
trap cleanup EXIT

# alive PID NAME LOG: fails naming the daemon and its log when it has exited.
alive() {
  kill -0 "$1" 2>/dev/null || fail "$2 exited; its log says: $(tail -n 20 "$3" 2>/dev/null)"
}

booted=$SECONDS
mungekey --create --keyfile="$tmp/key/munge.key"
munged -F --key-file="$tmp/key/munge.key" --socket="$tmp/run/munge.socket" \
  --pid-file="$tmp/run/munged.pid" --seed-file="$tmp/key/munged.seed" \
  --log-file="$tmp/log/munged.log" >"$tmp/log/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$tmp/run/munge.socket" ] && break; alive "${pids[0]}" munged "$tmp/log/munged.out"; sleep 0.2; done
[ -S "$tmp/run/munge.socket" ] || fail "munged did not create its socket in 10 s"

# Two free ports (others on this machine may run a Slurm of their own on 6817/6818).
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
port=16817
while ! port_free "$port" || ! port_free $((port + 1)); do port=$((port + 2)); done
node=$(hostname -s)
memory=$(awk '/^MemTotal:/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)
cat >"$tmp/slurm.conf" <<EOF
ClusterName=dpmtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/run/munge.socket
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/run/slurmctld.pid
SlurmdPidFile=$tmp/run/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
# No systemd, no cgroups in a container: track processes by their parents, bind nothing.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
MailProg=/bin/true
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
# Keep finished jobs' records for scontrol (there is no slurmdbd).
MinJobAge=3600
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$memory State=UNKNOWN
PartitionName=dpm Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$tmp/slurm.conf
slurmctld -D -f "$SLURM_CONF" >"$tmp/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N "$node" -f "$SLURM_CONF" >"$tmp/log/slurmd.out" 2>&1 &
pids+=($!)
state=
for _ in $(seq 60); do
  alive "${pids[1]}" slurmctld "$tmp/log/slurmctld.out"
  alive "${pids[2]}" slurmd "$tmp/log/slurmd.out"
  state=$(sinfo -h -n "$node" -o %t 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 1
done
[ "$state" = idle ] || fail "node $node is '${state:-not reported}' after 60 s, not idle"
echo "slurm: one-node cluster $node up in $((SECONDS - booted)) s (ports $port, $((port + 1)))"

# job_state ID: the JobState of every task of job ID, one a line.
job_state() { scontrol -o show job "$1" | grep -o 'JobState=[A-Z_]*' | cut -d= -f2; }
# wait_job ID: waits until job ID (every task of it) has ended; prints its states.
wait_job() {
  local deadline=$((SECONDS + timeout)) states
  while :; do
    states=$(job_state "$1")
    grep -qE 'PENDING|RUNNING|CONFIGURING|COMPLETING|SUSPENDED|REQUEUED' <<<"$states" || break
    [ $SECONDS -lt $deadline ] || fail "job $1 not done after $timeout s: $(tr '\n' ' ' <<<"$states")"
    alive "${pids[2]}" slurmd "$tmp/log/slurmd.out"
    sleep 1
  done
  sort -u <<<"$states" | tr '\n' ' '
}

# The render: the Cornell box, small, 4 shards of 2 passes.
sed 's/^resolution = .*/resolution = [96, 96]/' scenes/cornell-box.toml >"$tmp/box.toml"
export DPM_BIN=$dpm DPM_SCENE=$tmp/box.toml DPM_FILM_DIR=$tmp/films DPM_TASKS=4 \
  DPM_PASSES_PER_TASK=2 DPM_RENDER_ARGS="--caustic-photons 20000 --global-photons 20000" \
  DPM_DEPLOY_DIR=$repo/deploy
sbatch_args=(--cpus-per-task=1 "--chdir=$tmp" "--output=$tmp/log/%x-%j.out")
submitted=$SECONDS
ids=$(deploy/slurm/submit.sh "${sbatch_args[@]}")
read -r array merge <<<"$ids"
echo "slurm: submitted array $array (4 tasks) and merge $merge (afterok:$array)"
[ "$(wait_job "$array")" = "COMPLETED " ] || fail "array $array: $(job_state "$array" | tr '\n' ' ')"
[ "$(wait_job "$merge")" = "COMPLETED " ] || fail "merge $merge: $(job_state "$merge")"
echo "slurm: array and merge completed in $((SECONDS - submitted)) s"

# One machine, the same 8 passes (EXR like the shards: the film records the kernel field).
read -r -a flags <<<"$DPM_RENDER_ARGS"
"$dpm" render "$DPM_SCENE" --passes 8 "${flags[@]}" -o "$tmp/whole.exr" \
  --film "$tmp/whole.film" 2>"$tmp/log/whole.log"
"$compare" "$tmp/films/merged.exr" "$tmp/whole.exr" 1e-6 --per-pixel ||
  fail "the merged image differs from one run of the same passes"
"$dpm" merge "$tmp/films/merged.film" --expect 8 -o "$tmp/check.pfm" 2>&1 | grep -q '8 passes (0-7)' ||
  fail "the merged film does not hold passes 0-7"

# Resume: shard 2 lost. The merge alone fails naming its passes; the rerun of index 2 writes
# the same film; the merge after it passes.
mv "$tmp/films/shard-2.film" "$tmp/shard-2.first.film"
lonely=$(sbatch --parsable "${sbatch_args[@]}" deploy/slurm/merge.sbatch)
[ "$(wait_job "$lonely")" = "FAILED " ] || fail "merge $lonely without shard 2 did not fail"
grep -q 'passes 4-5 are missing' "$tmp/log/dpm-merge-$lonely.out" ||
  fail "merge $lonely's log does not name passes 4-5"
rerun=$(sbatch --parsable --array=2 "${sbatch_args[@]}" deploy/slurm/render.sbatch)
merge=$(sbatch --parsable --dependency=afterok:"$rerun" "${sbatch_args[@]}" deploy/slurm/merge.sbatch)
[ "$(wait_job "$rerun")" = "COMPLETED " ] || fail "rerun $rerun of index 2 did not complete"
[ "$(wait_job "$merge")" = "COMPLETED " ] || fail "merge $merge after the rerun did not complete"
cmp "$tmp/films/shard-2.film" "$tmp/shard-2.first.film" ||
  fail "the rerun of index 2 wrote another film"
"$compare" "$tmp/films/merged.exr" "$tmp/whole.exr" 1e-6 --per-pixel ||
  fail "after the rerun the merged image differs from one run"
echo "slurm: a lost shard failed the merge naming passes 4-5; its rerun wrote the same film"
echo "test-local-cluster.sh: ok in $((SECONDS - started)) s"
