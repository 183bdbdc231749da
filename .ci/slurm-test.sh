#!/usr/bin/env bash
# A study sharded over a real (single-node) Slurm job array, merged, and compared byte for
# byte with the same study run in one piece (docs/studies.md).
#
# Installs Debian's slurmctld, slurmd, slurm-client and munge (--no-install-recommends) when
# they are missing, starts munged, slurmctld and slurmd itself (the packages start no services
# in a container), runs a 4-task array of `shadelab study run --shard I/4`, merges, compares,
# and stops the daemons it started by their PIDs. Skips (exit 0, with the reason) where it
# cannot install or run Slurm: no apt-get, not root, or the install fails (no network). Fails
# (exit 1) when the array fails or the merged results differ from the unsharded run.
set -euo pipefail
cd "$(dirname "$0")/.."
started=$(date +%s)

step() {
  echo "== [$(($(date +%s) - started)) s] $*"
}
skip() {
  echo "slurm-test: SKIPPED: $*"
  exit 0
}
fail() {
  echo "slurm-test: FAILED: $*" >&2
  exit 1
}

need=(slurmctld slurmd sbatch sinfo munged)
missing=0
for b in "${need[@]}"; do command -v "$b" >/dev/null 2>&1 || missing=1; done
if [ "$missing" = 1 ]; then
  command -v apt-get >/dev/null 2>&1 || skip "Slurm is not installed and apt-get is not available"
  [ "$(id -u)" = 0 ] || skip "Slurm is not installed and installing it needs root"
  step "installing slurmctld slurmd slurm-client munge"
  if ! { DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
           slurmctld slurmd slurm-client munge >/dev/null 2>&1 ||
         { apt-get update -qq >/dev/null 2>&1 &&
           DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
             slurmctld slurmd slurm-client munge >/dev/null 2>&1; }; }; then
    skip "apt-get could not install slurmctld slurmd slurm-client munge (no network or no such packages)"
  fi
fi
[ "$(id -u)" = 0 ] || skip "starting munged, slurmctld and slurmd here needs root"

step "building shadelab (release)"
# Through `cargo test` so that the features (unified with the dev-dependencies) match the
# build .ci/run has just made: then this is a no-op rather than a second release build.
cargo test --release --quiet --no-run
bin="$PWD/target/release/shadelab"

work=$(mktemp -d /tmp/shadelab-slurm.XXXXXX)
pids=()
cleanup() {
  local status=$?
  # Stop only the daemons this script started, by PID, newest first.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill "${pids[$i]}" 2>/dev/null || true
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  if [ "$status" != 0 ]; then
    for log in "$work"/log/*; do
      [ -f "$log" ] && { echo "--- $log" >&2; tail -n 20 "$log" >&2; }
    done
  fi
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT

mkdir -p "$work"/{state,spool,log,shards,munge}
step "starting munged, slurmctld and slurmd"
host=$(hostname -s)

# munge: a key if the package made none, a socket folder it may write, run as user munge.
if [ ! -s /etc/munge/munge.key ]; then
  if command -v mungekey >/dev/null 2>&1; then
    mungekey --create --keyfile=/etc/munge/munge.key --force >/dev/null
  else
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
  fi
fi
chown munge:munge /etc/munge/munge.key
chmod 400 /etc/munge/munge.key
mkdir -p /run/munge /var/lib/munge /var/log/munge
chown munge:munge /run/munge /var/lib/munge /var/log/munge
chmod 755 /run/munge
setpriv --reuid=munge --regid=munge --init-groups \
  munged -F --force >"$work/log/munged.log" 2>&1 &
pids+=($!)
for _ in $(seq 50); do munge -n >/dev/null 2>&1 && break; sleep 0.1; done
munge -n >/dev/null 2>&1 || fail "munged did not start"

# One node: this machine, with the layout slurmd reports.
layout=$(slurmd -C | head -n 1 | sed -e 's/^NodeName=[^ ]* //')
export SLURM_CONF="$work/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=shadelab-ci
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
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
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
NodeName=$host NodeAddr=127.0.0.1 $layout State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -D -i >"$work/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D >"$work/log/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.2
done
[ "$state" = idle ] || fail "the node did not come up (state '$state')"

# The study: two stimuli with varied parameters, two slants, two priors, three rotations.
# Shapes are (height, width), as in every spec.
cat >"$work/spec.json" <<'EOF'
{
  "stimuli": [
    {"stimulus": "bumps", "params": {"rows": 1, "columns": 2, "pattern": ["alternate", "bumps"],
     "radius": 1, "spacing": 3}, "shape": [48, 96], "ppd": 16},
    {"stimulus": "sideways", "params": {"rows": 2, "columns": 1, "side": ["left", "right"]},
     "shape": [96, 48], "ppd": 16},
    {"stimulus": "crater", "params": {"rotation": ["0", "180"]}, "shape": [64, 64], "ppd": 10}
  ],
  "tilts": "0:360:20",
  "slants": [30, 45],
  "priors": {"kappa": [2, 4], "convexity_bias": [0, 1]},
  "rotations": "0,90,180"
}
EOF
cat >"$work/shard.sh" <<EOF
#!/usr/bin/env bash
set -euo pipefail
exec "$bin" --quiet --threads 1 study run "$work/spec.json" \\
  --shard "\$SLURM_ARRAY_TASK_ID/\$SLURM_ARRAY_TASK_COUNT" \\
  --out "$work/shards/shard-\$SLURM_ARRAY_TASK_ID"
EOF
chmod +x "$work/shard.sh"

step "sbatch --array=0-3 (4 shards)"
sbatch --wait --array=0-3 --job-name=shadelab-study --chdir="$work" \
  --output="$work/log/shard-%a.out" "$work/shard.sh" >"$work/log/sbatch.out" ||
  fail "the job array failed: $(cat "$work/log/sbatch.out") $(cat "$work"/log/shard-*.out 2>/dev/null)"
for i in 0 1 2 3; do
  [ -f "$work/shards/shard-$i/study.json" ] || fail "shard $i wrote no study.json"
done

step "merge, and the same study unsharded"
"$bin" --quiet study merge "$work"/shards/shard-* --out "$work/merged"
"$bin" --quiet study run "$work/spec.json" --out "$work/whole"
for f in results.csv sweep.csv; do
  cmp "$work/whole/$f" "$work/merged/$f" ||
    fail "$f of the merged shards differs from the unsharded run"
done
rows=$(($(wc -l <"$work/whole/results.csv") - 1))
echo "slurm-test: OK: 4 Slurm array tasks merged byte-identical to the unsharded run ($rows result rows) in $(($(date +%s) - started)) s"
