# tools/charts/recompute.gp — the recompute share against the fraction width, three panels:
# array cycles (first pass and first + refine), % of pixels recomputed on the host, host
# recompute seconds; one line per scene.
#   gnuplot -e "in='recompute_share.csv'; out='x.png'; note='...'; scenes='spheres64 showcase'" \
#     tools/charts/recompute.gp
# recompute_share.csv columns (tools/charts/recompute.sh): scene,policy,frac_bits,cycles,
# refine_cycles,refined,recomputed,recomputed_pct,host_recompute_s,array_host_s
# Solid lines: --uncertain auto (refine, then recompute); dashed: --uncertain recompute.
set terminal pngcairo size 900,1000 font ',10'
set output out
set datafile separator ','
set datafile missing 'NaN'
set grid
set key top left box opaque font ',9'
nsc = words(scenes)
sel(i, p) = strcol(1) eq word(scenes, i) && strcol(2) eq p
set multiplot layout 3,1 title 'Speed against accuracy: the share the host recomputes, by fraction width' margins 0.1,0.95,0.12,0.94 spacing 0,0.06
set xlabel 'fraction bits (--frac-bits)'
set logscale y
set ylabel 'array cycles (modelled)'
plot for [i=1:nsc] in using (sel(i, 'auto') ? column(3) : NaN):4 with linespoints lw 2 pt 7 lc i title word(scenes, i).' first pass', \
     for [i=1:nsc] in using (sel(i, 'auto') ? column(3) : NaN):($4 + $5) with linespoints lw 1 dt 2 pt 6 lc i title word(scenes, i).' + refine pass (auto)'
unset logscale y
set yrange [0:*]
set ylabel '% of pixels recomputed on the host'
plot for [i=1:nsc] in using (sel(i, 'auto') ? column(3) : NaN):8 with linespoints lw 2 pt 7 lc i title word(scenes, i).' auto', \
     for [i=1:nsc] in using (sel(i, 'recompute') ? column(3) : NaN):8 with linespoints lw 1 dt 2 pt 6 lc i title word(scenes, i).' recompute'
set yrange [*:*]
set logscale y
set ylabel 'host recompute seconds'
set label 1 note at screen 0.02, screen 0.02 left font ',8' noenhanced
plot for [i=1:nsc] in using (sel(i, 'auto') ? column(3) : NaN):9 with linespoints lw 2 pt 7 lc i title word(scenes, i).' auto', \
     for [i=1:nsc] in using (sel(i, 'recompute') ? column(3) : NaN):9 with linespoints lw 1 dt 2 pt 6 lc i title word(scenes, i).' recompute'
unset multiplot
