#!/bin/bash
#SBATCH --job-name=chambre
#SBATCH --array=0-3
#SBATCH --cpus-per-task=8
#SBATCH --output=chambre-%A_%a.log
# One shard of the render per array task: chambre reads the task's index from
# SLURM_ARRAY_TASK_ID (--shard auto/4; keep 4 equal to the array's size).
# SCENE and OUT come from the submitting shell (sbatch exports it), or default here.
set -euo pipefail
chambre render "${SCENE:-scene.toml}" -o "${OUT:-out.exr}" --shard auto/4 \
    --threads "$SLURM_CPUS_PER_TASK"
