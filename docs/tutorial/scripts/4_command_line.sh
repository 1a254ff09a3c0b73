#!/usr/bin/env bash
# Tutorial 4: the `bgphm` command line (docs/tutorial/4-command-line.md), as a script.
#
# Run it in an empty directory, where it writes its files; from the repository's root:
#     (cd "$(mktemp -d)" && bash "$OLDPWD/docs/tutorial/scripts/4_command_line.sh")
# Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it
# prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that.
set -euo pipefail

# %% Quick start: the demo
bgphm --quiet demo dc-motor --out demo

# %% Quick start: the demo
ls demo

# %% Model files
python - <<'EOF'
import json

model = json.load(open("demo/model.json"))
print(model["graph"])
print(model["nodes"][7])
print(model["links"][7])
EOF

# %% Model files
cat > motor.py <<'EOF'
from bondgraph.library import dc_motor

model = dc_motor(b=2e-4)                       # a worn bearing
inputs = {"U": lambda t: 12.0 * (t >= 0.1)}    # switched on at t = 0.1 s
t_end = 1.0
EOF

# %% `bgphm arr`: what can be monitored
bgphm --quiet arr demo/model.json --out report.md
grep '^#' report.md

# %% `bgphm arr`: what can be monitored
sed -n '3,5p' report.md | cut -d: -f1

# %% `bgphm arr`: what can be monitored
grep -A 7 '^### ARR_1_m' report.md

# %% `bgphm arr`: what can be monitored
grep -A 10 '^## Fault signatures' report.md

# %% `bgphm simulate`: records from the model
bgphm --quiet simulate motor.py --samples 5

# %% `bgphm simulate`: records from the model
bgphm --quiet simulate dc-motor --samples 1001 --out healthy.csv
bgphm --quiet simulate dc-motor --samples 1001 --set b=3e-4 --out worn.csv

# %% `bgphm simulate`: records from the model
bgphm --quiet simulate dc-motor --t-end 2 --samples 5 --degrade b=step:9e-4@1 --bias i=0.5@1.5 \
    --input U='12*step(t - 0.5)'

# %% The CSV format
head -n 1 demo/data.csv
wc -l < demo/data.csv                       # the header and 4001 samples

# %% The CSV format
cat > bad.csv <<'EOF'
t,U,i,omega
0,12,0,0
0.001,12,x,1.2
0.002,12,5.3,2.5
EOF
bgphm --quiet detect dc-motor bad.csv || echo "exit code $?"

# %% `bgphm detect`: alarms
bgphm detect demo/model.json demo/data.csv --calibrate 0.9 --window 21

# %% `bgphm detect`: alarms
bgphm --quiet detect dc-motor healthy.csv --margin 0.001

# %% `bgphm detect`: alarms
bgphm --quiet detect dc-motor worn.csv --margin 0.001

# %% `bgphm detect`: alarms
python - <<'EOF'
import json

summary = json.load(open("demo/detect/detection.json"))
print(summary["detection_time"], summary["alarming_arrs"])
print(summary["arrs"]["ARR_1_m"])
EOF

# %% `bgphm detect`: alarms
head -n 1 demo/detect/residuals.csv

# %% `bgphm prognose`: which parameter, which law, and the RUL
bgphm --quiet prognose demo/model.json demo/data.csv --fail b=2e-3 --fail J=2e-2 --calibrate 0.9 \
    --window 21 --dt 0.021

# %% `bgphm prognose`: which parameter, which law, and the RUL
bgphm --quiet prognose demo/model.json demo/data.csv --fail b=2e-3 --fail J=2e-2 --calibrate 0.9 \
    --window 21 --dt 0.021 --degradation exponential

# %% `bgphm prognose`: which parameter, which law, and the RUL
bgphm --quiet prognose demo/model.json demo/data.csv --fail b=2e-3 --fail J=2e-2 --calibrate 0.9 \
    --window 21 --dt 0.021 --degradation linear

# %% `bgphm prognose`: which parameter, which law, and the RUL
python - <<'EOF'
import json

prognosis = json.load(open("demo/prognose/prognosis.json"))
print(sorted(prognosis))
print(prognosis["candidate"], prognosis["status"], sorted(prognosis["evidence"]))
print(prognosis["same_signature"])   # J fires the same ARRs: the model cannot isolate b
print(sorted(prognosis["last"]))
truth = json.load(open("demo/truth.json"))
print(truth["candidate"], truth["rate"], truth["failure_value"], round(truth["eol"], 3))
EOF

# %% `bgphm prognose`: which parameter, which law, and the RUL
head -n 1 demo/prognose/estimates.csv

# %% `bgphm prognose`: which parameter, which law, and the RUL
head -n 1 demo/prognose/rul.csv

# %% The same run in Python
bgphm --quiet prognose demo/model.json demo/data.csv --fail b=2e-3 --fail J=2e-2 --calibrate 0.9 \
    --window 21 --dt 0.021 --out same

# %% The same run in Python
cat > same_run.py <<'EOF'
import json

from bondgraph.io import load_model
from diagnosis import DetectionSettings, derive_arrs, read_csv
from prognosis import IsolationSettings, PrognosisSettings, prognose

spec = load_model("demo/model.json")
settings = PrognosisSettings(detection=DetectionSettings(calibrate=0.9, window=21),
                             isolation=IsolationSettings(dt=0.021))
result = prognose(derive_arrs(spec.model), read_csv("demo/data.csv"), {"b": 2e-3, "J": 2e-2}, settings,
                  domains=spec.model.domains)
python = json.loads(json.dumps(result.as_dict(), default=float))   # as prognosis.json holds it
cli = json.load(open("same/prognosis.json"))
print(python["predictions"] == cli["predictions"] and python["evidence"] == cli["evidence"])
print(python["status"], python["degradation"], round(python["last"]["rul_median"], 4), python["filter_step"])
EOF
python same_run.py

# %% Exit codes
bgphm --quiet simulate dc-motor --set c=1 || echo "exit code $?"
bgphm --quiet detect dc-motor missing.csv || echo "exit code $?"
bgphm --quiet detect nowhere.json demo/data.csv || echo "exit code $?"
bgphm --quiet prognose dc-motor demo/data.csv --degradation linear || echo "exit code $?"
