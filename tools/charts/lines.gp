# tools/charts/lines.gp — one line per column of a CSV against its first column.
# Called by tools/charts.sh:
#   gnuplot -e "in='f.csv'; out='f.png'; ttl='...'; xl='...'; yl='...'; note='...';
#               ncols=N; logx=0; logy=1; empty=0 [; pairs=K]" tools/charts/lines.gp
# The CSV has a header row (the line titles); NaN marks a value not measured. `note` is
# printed under the plot (and `note2`, `note3` under it) (skipped methods, oversubscription, what "model"/"host" mean).
set terminal pngcairo size 900,600 font ',10'
set output out
set datafile separator ','
set datafile missing 'NaN'
set title ttl
set xlabel xl
set ylabel yl
set grid
set key top left box opaque
set bmargin 9
if (logx) set logscale x 2
if (logy) set logscale y
if (strlen(note) > 0) set label 1 note at screen 0.02, screen 0.08 left font ',8' noenhanced
if (exists('note2') && strlen(note2) > 0) set label 3 note2 at screen 0.02, screen 0.05 left font ',8' noenhanced
if (exists('note3') && strlen(note3) > 0) set label 4 note3 at screen 0.02, screen 0.02 left font ',8' noenhanced
if (empty) {
  set xrange [0:1]; set yrange [0:1]; unset logscale
  set label 2 'no data: the methods of this chart are not available yet' at graph 0.5, graph 0.5 center
  plot 2 notitle
} else {
  if (exists('pairs')) {
    # Columns 2..pairs+1 dashed and the next `pairs` solid in the same colours (one method
    # two ways: exhaustive, then with a BVH); any column after them in the next colours.
    dashof(i) = i <= pairs + 1 ? 2 : 1
    colourof(i) = i <= pairs + 1 ? i - 1 : i - 1 - pairs
    plot for [i=2:ncols] in using 1:i with linespoints lw 2 pt (i+4) \
      dt dashof(i) lc colourof(i) title columnheader(i)
  } else {
    plot for [i=2:ncols] in using 1:i with linespoints lw 2 pt (i+4) title columnheader(i)
  }
}
