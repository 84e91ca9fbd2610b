# Heading error against the distance flown for the three in-flight alignment methods
# (track CSVs written by `navtwin inflight-align --track_csv`: t_s, path_length_km,
# yaw_deg, sigma_arcmin, error_arcmin). docs/inflight/plot.sh runs the experiment.
# Usage: gnuplot -e "dir='TRACKS'; outdir='docs/inflight'" docs/inflight/heading_vs_distance.gp
if (!exists("dir")) dir = '.'
if (!exists("outdir")) outdir = '.'
set datafile separator ','
set datafile columnheaders
set terminal pngcairo size 900,520 font 'sans,11' noenhanced
set xlabel 'distance flown (km)'
set ylabel 'heading error (arcmin)'
set grid
set key top right
set xrange [0:*]

set output outdir . '/heading_vs_distance.png'
set title 'inflight-mach07-south, seed 1: heading error (lines) and 1 sigma (dashed)'
set yrange [-25:25]
plot dir.'/clean_distance.csv' using 2:5 with lines lw 2 lc rgb '#1f77b4' title 'distance method', \
     dir.'/clean_distance.csv' using 2:4 with lines dt 2 lc rgb '#1f77b4' notitle, \
     dir.'/clean_kalman.csv' using 2:5 with lines lw 2 lc rgb '#d62728' title 'Kalman only', \
     dir.'/clean_kalman.csv' using 2:4 with lines dt 2 lc rgb '#d62728' notitle, \
     dir.'/clean_batch.csv' using 2:5 with lines lw 2 lc rgb '#2ca02c' title 'batch (smoothed, whole flight)', \
     dir.'/clean_batch.csv' using 2:4 with lines dt 2 lc rgb '#2ca02c' notitle

set output outdir . '/heading_vs_distance_zoom.png'
set title 'the same, last 100 km'
set xrange [20:*]
set yrange [-6:6]
replot

set output outdir . '/heading_vs_distance_outliers.png'
set title 'with 1 % GPS outliers of 200 m'
set xrange [0:*]
set yrange [-25:25]
plot dir.'/outliers_distance.csv' using 2:5 with lines lw 2 lc rgb '#1f77b4' title 'distance method', \
     dir.'/outliers_kalman.csv' using 2:5 with lines lw 2 lc rgb '#d62728' title 'Kalman only', \
     dir.'/outliers_batch.csv' using 2:5 with lines lw 2 lc rgb '#2ca02c' title 'batch, Cauchy loss', \
     dir.'/outliers_batch_noloss.csv' using 2:5 with lines lw 2 dt 3 lc rgb '#2ca02c' title 'batch, no robust loss'
