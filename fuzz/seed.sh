#!/bin/sh
# Copies the binary models of the test corpus (../shared/models, or $VOXEL_ART_MODELS) into the fuzz corpus
# folder as seeds. The copies are never committed (fuzz/.gitignore).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
models=${VOXEL_ART_MODELS:-$here/../../shared/models}
seeds=$here/corpus/import_voxelize
mkdir -p "$seeds"
find "$models" -name '*.glb' -exec cp {} "$seeds/" \;
echo "seeded $(ls "$seeds" | wc -l) files into $seeds"
