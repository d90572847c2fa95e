# vs2.sh SCENE DEPTH SPP TAG METHOD SEEDS
S=$1; D=$2; N=$3; b=$4; M=$5
for seed in $6; do
/tmp/lanterna_old render $S --method $M --source tree --spp $N --max-depth $D --width 96 --height 72 --seed $seed -o ${b}_old_$seed.exr >/dev/null 2>&1
/work/main/target/release/lanterna render $S --method $M --source tree --spp $N --max-depth $D --width 96 --height 72 --seed $seed -o ${b}_new_$seed.exr >/dev/null 2>&1
done
