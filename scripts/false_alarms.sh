#!/bin/sh
# False alarms on clean data without stated noise: seeds x {constant, sine, stop-go}.
O=${O:-target/release/obsan}
for seed in $SEEDS; do for prof in constant sine:0.5:60 stopgo:20:10; do
  d=$(mktemp -d)/c; $O simulate --out $d --speed-profile $prof --seed $seed >/dev/null 2>&1
  python3 -c "import json,sys; p=sys.argv[1]+'/dataset.json'; j=json.load(open(p)); j.pop('noise',None); json.dump(j,open(p,'w'))" $d
  for m in $MODES; do
    n=$($O diagnose --model systems/calib.sys --effects systems/calib.eff --data $d --input-noise $m | grep '^named:' | tr '\n' ' ')
    echo "$seed $prof $m $n"
  done
done; done
