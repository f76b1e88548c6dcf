#!/bin/bash
# Submit the shards as an array job and the merge as a job that waits for all of them.
set -euo pipefail
export SCENE=/shared/assets/scene.glb BAKE_ARGS="--directions 129 --tiles 128" OUT=/shared/farm/scene
shards=$(sbatch --parsable bake-shard.sbatch)
sbatch --dependency=afterok:"$shards" merge.sbatch
