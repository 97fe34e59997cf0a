#!/usr/bin/env bash
# The shipped model from scratch (`make model`): simulated data → staged training → int8 bundle →
# the evaluation tables. Every step is skipped when its output exists and training resumes from
# its checkpoint, so an interrupted run continues where it stopped.
#
#   WORK=~/.cache/cavatar-model  where datasets and runs go (≈ 4 GB)
#   BUNDLE=edge/models/lean-96   the bundle written; EVAL=docs/model  the tables written
#   STEPS_FRAMES / STEPS_HEAD    training steps of the two stages
#
# Measured on the 2-core CPU machine this project develops on (shared with other work): data ≈ 11 min,
# frames stage ≈ 32 min (0.39–0.6 s/step on the board's path), head stage ≈ 14 min (with its feature cache), bundle
# 2 min, tables and the fine-tuning sweep ≈ 25 min (2026-11-29; an earlier run: 30, 55, 20 min). With CUDA,
# training uses the GPU.
set -euo pipefail
CAVATAR=${CAVATAR:-.venv/bin/cavatar}
PY=${PY:-.venv/bin/python}
WORK=${WORK:-$HOME/.cache/cavatar-model}
BUNDLE=${BUNDLE:-edge/models/lean-96}
EVAL=${EVAL:-docs/model}
STEPS_FRAMES=${STEPS_FRAMES:-3500}
STEPS_HEAD=${STEPS_HEAD:-2000}
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
D=$WORK/data R=$WORK/runs
mkdir -p "$D" "$R" "$EVAL"

gen() {  # gen NAME ARGS...: one dataset, unless it is complete already
  local name=$1; shift
  [ -f "$D/$name/manifest.json" ] || { rm -rf "$D/$name"; "$CAVATAR" sim generate --out "$D/$name" --workers 2 "$@"; }
}
# Every dataset carries its carpets' installer calibrations, and training reads the board's path (raw
# sensor-model counts → calibration.apply → kPa, floored and clipped as the runtime does: --input board).
# 96 subjects (seed 2): ~77 train, ~10 val (model selection), ~9 test; two- and three-person scenes of
# seed 0's subjects; a held-out multi-person set (seed 101).
# The paper's ten activities and walking, as the live carpet draws them (walking joined on 2026-11-29:
# the model had never seen it, and published walkers at MPJPE 33.9 cm, 57 % of frames facing backwards).
CAL=(--calibration installer --activities stepping,bending,turning,squat,twisting,raising_arms,lunge,sitting,push_up,sit_up,walking)
gen many96 --subjects 96 --seconds-per-activity 8 --people 1 --seed 2 "${CAL[@]}"
gen multi_train --subjects 12 --seconds-per-activity 15 --people 2..3 --seed 0 "${CAL[@]}"
gen multi_eval --subjects 6 --seconds-per-activity 10 --people 1..3 --seed 101 "${CAL[@]}"
gen unseen888 --subjects 4 --seconds-per-activity 6 --seed 888 "${CAL[@]}"

DATA=(--data "$D/many96" --data "$D/multi_train")
"$CAVATAR" train --stage frames --input board "${DATA[@]}" --out "$R/frames" --steps "$STEPS_FRAMES" --batch 128 --lr 1e-3 \
  --lr-schedule cosine --optimizer adamw --threads 1 --val-every 500 --checkpoint-every 100 --resume
"$CAVATAR" train --stage head --input board "${DATA[@]}" --init "$R/frames/best.pt" --out "$R/head" --steps "$STEPS_HEAD" --batch 64 --cache-copies 4 \
  --lr 1e-3 --lr-schedule cosine --optimizer adamw --threads 2 --val-every 500 --checkpoint-every 100 --resume

"$CAVATAR" bundle "$R/head/best.pt" --data "$D/many96" --out "$BUNDLE" --name lean-96
# The heading resolver's parameters (edge/infer/heading.json) are not refitted here: `make heading` fits them
# on seed 5151's short tracks, and the end-to-end score decides whether a refit is kept. For the bundle of
# 2026-11-29 it was not: the refit gave 4.57 % of the standard score's frames over 90° off, the kept
# parameters 3.15 %, and no resolver 8.83 % (docs/model.md).
for INPUT in clean board; do
  SUFFIX=$([ "$INPUT" = board ] && echo "-board" || true)
  "$CAVATAR" eval --bundle "$BUNDLE" --data "$D/many96" --split test --input "$INPUT" --out "$EVAL/eval-test$SUFFIX" \
    --title "lean-96 int8 on the 10 unseen subjects of seed 2 (one person), input: $INPUT"
  "$CAVATAR" eval --bundle "$BUNDLE" --data "$D/unseen888" --split all --input "$INPUT" --out "$EVAL/eval-unseen-888$SUFFIX" \
    --title "lean-96 int8, heading resolved, on 4 unseen subjects (seed 888), input: $INPUT"
done
"$CAVATAR" eval --bundle "$BUNDLE" --data "$D/multi_eval" --split all --people 2..3 --out "$EVAL/eval-multi" \
  --title "lean-96 int8 on unseen subjects, two and three people"
"$CAVATAR" eval --bundle "$BUNDLE" --data "$D/multi_eval" --split all --people 1 --out "$EVAL/eval-new6-alone" \
  --title "lean-96 int8 on six more unseen subjects (seed 101), alone"
"$CAVATAR" eval --bundle "$BUNDLE" --data "$D/many96" --protocol seen-time --out "$EVAL/eval-seen-time" \
  --title "lean-96 int8, the paper's protocol (training subjects of seed 2, last 10 % in time)"
"$PY" -m export.tables --readme README.md "unseen=$EVAL/eval-test.json" \
  "unseen, board's path=$EVAL/eval-test-board.json" "seen-time=$EVAL/eval-seen-time.json"
"$PY" -m export.sweep --bundle "$BUNDLE" --data "$D/many96" --split test --subject s19 --subject s25 \
  --fractions 0,0.1,0.3,0.6 --steps 300 --lr 3e-4 --stage head --precision fp32 --out "$EVAL/finetune"
echo "bundle: $BUNDLE; tables: $EVAL/eval-test.md, $EVAL/eval-multi.md, $EVAL/finetune.md"
