# Slave attitude error of transfer alignment against the transfer delay (issue 6).
# Called by docs/transfer/plot.sh with dir (the folder holding order1.dat, order2.dat,
# batch.dat: columns delay_ms method roll pitch heading RMS, roll pitch heading max (mrad),
# delay estimate and sigma (ms), misalignment error (mrad)) and outdir.
set terminal pngcairo size 900,900 font ",11"
if (!exists("tag")) tag = ''
if (!exists("scenario")) scenario = 'transfer-alignment-high-maneuver'
set output outdir.'/error_vs_delay'.tag.'.png'
set multiplot layout 2,1 title scenario.", seed 1: slave attitude error RMS (after settle\\_s) vs transfer delay"
set grid
set logscale y
set format y "%g"
set xrange [-10:510]
set xtics 0,50,500
set key outside right top
# The same plot area in both panels (the keys differ in width).
set lmargin at screen 0.09
set rmargin at screen 0.64
set xlabel "transfer delay (ms)"
set ylabel "heading RMS (mrad)"
plot dir.'/order1.dat' using 1:5 with linespoints lw 2 pt 7 title "order1 (rate only)", \
     dir.'/order2.dat' using 1:5 with linespoints lw 2 pt 5 title "order2 (+ ang. acc., acc.)", \
     dir.'/batch.dat'  using 1:5 with linespoints lw 2 pt 9 title "batch (Ceres)"
set ylabel "roll / pitch RMS (mrad)"
plot dir.'/order1.dat' using 1:3 with linespoints lw 2 pt 7 lc 1 title "order1 roll", \
     dir.'/order1.dat' using 1:4 with linespoints lw 2 pt 6 lc 1 dt 2 title "order1 pitch", \
     dir.'/order2.dat' using 1:3 with linespoints lw 2 pt 5 lc 2 title "order2 roll", \
     dir.'/order2.dat' using 1:4 with linespoints lw 2 pt 4 lc 2 dt 2 title "order2 pitch", \
     dir.'/batch.dat'  using 1:3 with linespoints lw 2 pt 9 lc 3 title "batch roll", \
     dir.'/batch.dat'  using 1:4 with linespoints lw 2 pt 8 lc 3 dt 2 title "batch pitch"
unset multiplot
