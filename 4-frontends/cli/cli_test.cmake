# Run by ctest with -DDISPEL=<path to the dispel executable>: checks the command-line contract.
function(run_dispel out_rc out_stdout out_stderr)
  execute_process(COMMAND ${DISPEL} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE so ERROR_VARIABLE se
                  TIMEOUT 120)
  set(${out_rc} "${rc}" PARENT_SCOPE)
  set(${out_stdout} "${so}" PARENT_SCOPE)
  set(${out_stderr} "${se}" PARENT_SCOPE)
endfunction()

# bench --json prints {"results": [{"name", "beams", "median_ns"}]} and nothing else on stdout.
run_dispel(rc so se bench --json --filter "^(segmentation|reference_dbscan)/1617/"
           --repetitions 1 --min-time 0.01)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "bench --json failed (${rc}): ${se}")
endif()
string(JSON count LENGTH "${so}" results)
if(NOT count EQUAL 2)
  message(FATAL_ERROR "expected 2 results, got ${count}: ${so}")
endif()
foreach(i 0 1)
  string(JSON name GET "${so}" results ${i} name)
  string(JSON beams GET "${so}" results ${i} beams)
  string(JSON median GET "${so}" results ${i} median_ns)
  if(NOT name MATCHES "^(segmentation|reference_dbscan)$" OR NOT beams EQUAL 1617
     OR NOT median GREATER 0)
    message(FATAL_ERROR "bad result ${i}: ${so}")
  endif()
endforeach()

# Bad input: a clear one-line error on stderr and a non-zero exit, never a crash.
foreach(case "bench;--repetitions;0" "bench;--min-time;-1" "bench;--filter;no_such_case" "frob" "")
  run_dispel(rc so se ${case})
  if(rc EQUAL 0 OR NOT rc MATCHES "^[0-9]+$")
    message(FATAL_ERROR "'dispel ${case}' exited '${rc}', expected a non-zero exit code")
  endif()
  if(se STREQUAL "")
    message(FATAL_ERROR "'dispel ${case}' printed no error")
  endif()
endforeach()
message(STATUS "command-line contract holds")

if(NOT HAVE_IO)
  return()
endif()

# dispel filter: bad input gives one line on stderr, a non-zero exit, and no output file.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(out ${WORK_DIR}/out.bag)
file(WRITE ${WORK_DIR}/not_a_bag.bag "hello\n")
file(WRITE ${WORK_DIR}/unknown_key.yaml "segmentation:\n  cluster_gapm: 0.1\n")
file(WRITE ${WORK_DIR}/negative_eps.yaml "segmentation:\n  cluster_gap_m: -0.1\n")
# The first 1 MB of the real bag: truncated.
execute_process(COMMAND head -c 1000000 ${BAG} OUTPUT_FILE ${WORK_DIR}/truncated.bag)

function(expect_filter_error expected)
  file(REMOVE ${out})
  run_dispel(rc so se filter ${ARGN} -o ${out})
  if(rc EQUAL 0)
    message(FATAL_ERROR "'dispel filter ${ARGN}' succeeded; expected: ${expected}")
  endif()
  string(STRIP "${se}" line)
  if(NOT line MATCHES "${expected}" OR line MATCHES "\n")
    message(FATAL_ERROR "'dispel filter ${ARGN}': expected one line matching '${expected}', got:\n${se}")
  endif()
  if(EXISTS ${out} OR EXISTS ${out}.partial)
    message(FATAL_ERROR "'dispel filter ${ARGN}' left an output file")
  endif()
endfunction()

expect_filter_error("No such file" ${WORK_DIR}/missing.bag --static-sensor)
expect_filter_error("not a readable ROS 1 bag" ${WORK_DIR}/not_a_bag.bag --static-sensor)
expect_filter_error("truncated.bag" ${WORK_DIR}/truncated.bag --static-sensor)
expect_filter_error("no sensor_msgs/LaserScan topic /front" ${BAG} --static-sensor --scan-topic /front)
expect_filter_error("no nav_msgs/Odometry topic /odom" ${BAG}
                    --config ${SOURCE_DIR}/config/thesis.yaml)
expect_filter_error("--odom-topic none needs the scan registration" ${BAG} --odom-topic none
                    --config ${SOURCE_DIR}/config/thesis.yaml)
expect_filter_error("unknown key 'segmentation.cluster_gapm'" ${BAG} --static-sensor
                    --config ${WORK_DIR}/unknown_key.yaml)
expect_filter_error("segmentation.cluster_gap_m must be" ${BAG} --static-sensor
                    --config ${WORK_DIR}/negative_eps.yaml)
expect_filter_error("cannot open the configuration file" ${BAG} --static-sensor
                    --config ${WORK_DIR}/missing.yaml)

# A good run: the bag and the statistics.
file(REMOVE ${out})
run_dispel(rc so se filter ${BAG} -o ${out} --static-sensor --scale-to-scanner
           --stats ${WORK_DIR}/stats.json)
if(NOT rc EQUAL 0 OR NOT EXISTS ${out})
  message(FATAL_ERROR "dispel filter failed (${rc}): ${se}")
endif()
if(NOT so MATCHES "1265 scans")
  message(FATAL_ERROR "no summary: ${so}")
endif()
file(READ ${WORK_DIR}/stats.json stats)
string(JSON total GET "${stats}" scans total)
string(JSON processed GET "${stats}" scans processed)
string(JSON dynamic GET "${stats}" beams_removed dynamic)
string(JSON median GET "${stats}" scan_time_us median)
string(JSON p99 GET "${stats}" scan_time_us p99)
string(JSON p99_9 GET "${stats}" scan_time_us p99_9)
string(JSON max GET "${stats}" scan_time_us max)
string(JSON cpu_median GET "${stats}" scan_cpu_time_us median)
string(JSON cpu_max GET "${stats}" scan_cpu_time_us max)
string(JSON tracks GET "${stats}" tracks_created)
string(JSON min_points GET "${stats}" config min_points)
if(NOT total EQUAL 1265 OR NOT processed EQUAL 1265 OR NOT dynamic GREATER 10000
   OR NOT median GREATER 0 OR p99 LESS median OR p99_9 LESS p99 OR max LESS p99_9
   OR NOT cpu_median GREATER 0 OR cpu_max LESS cpu_median OR NOT tracks GREATER 10
   OR NOT min_points EQUAL 4)
  message(FATAL_ERROR "bad statistics: ${stats}")
endif()
# The five scans that cost the most CPU time, the costliest first, each with what it did.
string(JSON slow_count LENGTH "${stats}" slowest_scans)
if(NOT slow_count EQUAL 5)
  message(FATAL_ERROR "slowest_scans: ${slow_count} entries, 5 expected: ${stats}")
endif()
set(previous_cpu "")
foreach(k RANGE 4)
  string(JSON cpu GET "${stats}" slowest_scans ${k} cpu_time_us)
  string(JSON beams GET "${stats}" slowest_scans ${k} beams)
  string(JSON index GET "${stats}" slowest_scans ${k} index)
  string(JSON event GET "${stats}" slowest_scans ${k} event)
  if(cpu GREATER cpu_max OR cpu LESS cpu_median OR beams LESS 1 OR index LESS 0
     OR NOT index LESS 1265 OR event STREQUAL "")
    message(FATAL_ERROR "slowest_scans[${k}]: ${stats}")
  endif()
  if(NOT previous_cpu STREQUAL "" AND cpu GREATER previous_cpu)
    message(FATAL_ERROR "slowest_scans not costliest first: ${stats}")
  endif()
  set(previous_cpu ${cpu})
endforeach()

# The heap made resident before the first scan (16 MB by default; 0 under a sanitizer's
# allocator) changes no output: the same bag without it.
string(JSON heap GET "${stats}" resident_heap_bytes)
if(NOT heap EQUAL 16777216 AND NOT heap EQUAL 0)
  message(FATAL_ERROR "resident_heap_bytes ${heap}, expected 16 MB (or 0 under a sanitizer)")
endif()
set(no_heap ${WORK_DIR}/no_heap.bag)
file(REMOVE ${no_heap})
run_dispel(rc so se filter ${BAG} -o ${no_heap} --static-sensor --scale-to-scanner
           --resident-heap-mb 0 --stats ${WORK_DIR}/no_heap.json)
file(READ ${WORK_DIR}/no_heap.json no_heap_stats)
string(JSON heap GET "${no_heap_stats}" resident_heap_bytes)
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${out} ${no_heap} RESULT_VARIABLE differ)
if(NOT rc EQUAL 0 OR NOT heap EQUAL 0 OR NOT differ EQUAL 0)
  message(FATAL_ERROR "--resident-heap-mb 0: rc ${rc}, resident_heap_bytes ${heap}, bags differ: "
                      "${differ}; ${se}")
endif()
file(REMOVE ${no_heap})
expect_filter_error("--resident-heap-mb: Value -1 not in range 0 to 4096" ${BAG} --static-sensor
                    --resident-heap-mb -1)

# Ctrl-C: either interrupted with nothing written, or already done with a complete bag. A signal
# that comes while the program is still loading its shared libraries (MRPT's, for rawlogs, take
# about 0.1 s; more on a busy machine) ends it before its handler is installed, silently: then
# the run is repeated with a later signal, up to 8 s: on a machine busy with a build and other
# tests, starting can take longer than 2 s; a later signal finds the run interrupted or done.
foreach(delay 0.2 0.5 1.0 2.0 4.0 8.0)
  file(REMOVE ${out})
  execute_process(COMMAND timeout --preserve-status -s INT ${delay} ${DISPEL} filter ${BAG} -o ${out}
                          --static-sensor --compression bz2
                  RESULT_VARIABLE rc OUTPUT_VARIABLE so ERROR_VARIABLE se)
  if(NOT (rc EQUAL 130 AND se STREQUAL "" AND so STREQUAL "" AND NOT EXISTS ${out}
          AND NOT EXISTS ${out}.partial))
    break()
  endif()
endforeach()
if(EXISTS ${out}.partial)
  message(FATAL_ERROR "an interrupted run left ${out}.partial")
endif()
if(rc EQUAL 130)
  if(EXISTS ${out} OR NOT se MATCHES "interrupted")
    message(FATAL_ERROR "interrupted run: wrote ${out} or said nothing: ${se}")
  endif()
elseif(NOT rc EQUAL 0 OR NOT EXISTS ${out})
  message(FATAL_ERROR "run under SIGINT ended with ${rc}: ${se}")
endif()
message(STATUS "dispel filter contract holds (SIGINT run exit ${rc})")

# dispel sim and dispel eval: a short simulated run, filtered and evaluated.
set(sim ${WORK_DIR}/sim.bag)
run_dispel(rc so se sim ${SOURCE_DIR}/config/scenarios/thesis_hall.yaml -o ${sim} --seed 3
           --duration 4)
if(NOT rc EQUAL 0 OR NOT EXISTS ${sim})
  message(FATAL_ERROR "dispel sim failed (${rc}): ${se}")
endif()
run_dispel(rc so se filter ${sim} -o ${WORK_DIR}/sim_filtered.bag
           --config ${SOURCE_DIR}/config/default_masked.yaml)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dispel filter on the simulation failed (${rc}): ${se}")
endif()
run_dispel(rc so se eval --truth ${sim} --result ${WORK_DIR}/sim_filtered.bag --json)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dispel eval failed (${rc}): ${se}")
endif()
string(JSON pres GET "${so}" preservation_rate)
string(JSON scans GET "${so}" scans)
string(JSON static_beams GET "${so}" per_class static beams)
string(JSON latency_type TYPE "${so}" detection_latency_s)
string(JSON f1_type TYPE "${so}" f1)
# The still beams of actors seen moving later are a part of the still beams.
string(JSON still_beams GET "${so}" per_class still beams)
string(JSON still_later_beams GET "${so}" per_class still_moves_later beams)
string(JSON still_later_type TYPE "${so}" per_class still_moves_later removed_rate)
if(NOT scans EQUAL 81 OR NOT static_beams GREATER 0 OR pres LESS 0.99
   OR NOT latency_type STREQUAL "OBJECT" OR NOT f1_type MATCHES "NUMBER|NULL"
   OR still_later_beams GREATER still_beams OR NOT still_later_type MATCHES "NUMBER|NULL")
  message(FATAL_ERROR "bad evaluation: ${so}")
endif()
# --map: the maps from the true poses; the figures are counts of cells and shares of them.
run_dispel(rc so se eval --truth ${sim} --result ${WORK_DIR}/sim_filtered.bag --json --map
           --map-resolution 0.1)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dispel eval --map failed (${rc}): ${se}")
endif()
string(JSON map_scans GET "${so}" map scans)
string(JSON map_res GET "${so}" map resolution_m)
string(JSON oracle_cells GET "${so}" map oracle_occupied_cells)
string(JSON raw_wrong GET "${so}" map raw wrongly_occupied_cells)
string(JSON result_wrong GET "${so}" map result wrongly_occupied_cells)
string(JSON result_lost GET "${so}" map result lost_share)
if(NOT map_scans GREATER 75 OR NOT map_res EQUAL 0.1 OR NOT oracle_cells GREATER 0
   OR result_wrong GREATER raw_wrong OR NOT result_lost GREATER_EQUAL 0)
  message(FATAL_ERROR "bad map evaluation: ${so}")
endif()

file(WRITE ${WORK_DIR}/bad_scenario.yaml "lidar: {range_limt_m: 5}\n")
function(expect_error_no_output expected output)
  file(REMOVE ${output})
  run_dispel(rc so se ${ARGN})
  string(STRIP "${se}" line)
  if(rc EQUAL 0 OR NOT line MATCHES "${expected}" OR line MATCHES "\n" OR EXISTS ${output})
    message(FATAL_ERROR "'dispel ${ARGN}': expected one line matching '${expected}', a non-zero "
                        "exit and no ${output}; got ${rc}:\n${se}")
  endif()
endfunction()
expect_error_no_output("unknown key 'lidar.range_limt_m'" ${WORK_DIR}/x.bag
                       sim ${WORK_DIR}/bad_scenario.yaml -o ${WORK_DIR}/x.bag)
expect_error_no_output("cannot open the scenario file" ${WORK_DIR}/x.bag
                       sim ${WORK_DIR}/missing.yaml -o ${WORK_DIR}/x.bag)
expect_error_no_output("no /scan_truth" ${WORK_DIR}/x.bag
                       eval --truth ${BAG} --result ${WORK_DIR}/sim_filtered.bag)
expect_error_no_output("no /scan_labels or /scan_filtered" ${WORK_DIR}/x.bag
                       eval --truth ${sim} --result ${sim})
expect_error_no_output("no nav_msgs/Odometry topic /ground_truth.*true poses" ${WORK_DIR}/x.bag
                       eval --truth ${BAG} --result ${WORK_DIR}/sim_filtered.bag --map)
expect_error_no_output("map-resolution" ${WORK_DIR}/x.bag
                       eval --truth ${sim} --result ${WORK_DIR}/sim_filtered.bag --map
                       --map-resolution 0)
message(STATUS "dispel sim and eval contract holds")

# dispel odom and dispel eval-trajectory: the simulated run's wheels and IMU against its truth.
set(traj ${WORK_DIR}/trajectory.csv)
set(truth ${WORK_DIR}/truth.csv)
run_dispel(rc so se odom ${sim} -o ${traj} --model ct --truth-csv ${truth} --json)
if(NOT rc EQUAL 0 OR NOT EXISTS ${traj} OR NOT EXISTS ${truth})
  message(FATAL_ERROR "dispel odom failed (${rc}): ${se}")
endif()
string(JSON model GET "${so}" model)
string(JSON wheel_source GET "${so}" wheel_source)
string(JSON rows GET "${so}" rows)
if(NOT model STREQUAL "ct" OR NOT wheel_source STREQUAL "/wheels" OR rows LESS 200)
  message(FATAL_ERROR "bad odom statistics: ${so}")
endif()
run_dispel(rc so se eval-trajectory --truth ${truth} --estimate ${traj} --json)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dispel eval-trajectory failed (${rc}): ${se}")
endif()
foreach(key rmse_position_m rmse_yaw_rad final_position_error_m final_yaw_error_rad path_length_m)
  string(JSON value GET "${so}" ${key})
  if(value STREQUAL "" OR value MATCHES "null")
    message(FATAL_ERROR "eval-trajectory: no ${key} in ${so}")
  endif()
endforeach()
string(JSON rmse GET "${so}" rmse_position_m)
if(rmse GREATER 0.5)
  message(FATAL_ERROR "odometry of a 4 s simulated run is off by ${rmse} m: ${so}")
endif()
expect_error_no_output("no_such.bag: not a readable ROS 1 bag" ${WORK_DIR}/x.csv
                       odom ${WORK_DIR}/no_such.bag -o ${WORK_DIR}/x.csv)
expect_error_no_output("which topic holds the wheel speeds" ${WORK_DIR}/x.csv
                       odom ${BAG} -o ${WORK_DIR}/x.csv)
expect_error_no_output("cannot open the file" ${WORK_DIR}/x.csv
                       eval-trajectory --truth ${WORK_DIR}/missing.csv --estimate ${traj})
message(STATUS "dispel odom and eval-trajectory contract holds")

# dispel render: a map of the shipped recording (a stationary scanner), and a bad view.
set(picture ${WORK_DIR}/render.png)
file(REMOVE ${picture})
run_dispel(rc so se render ${BAG} -o ${picture} --static-sensor --size 800x600)
if(NOT rc EQUAL 0 OR NOT EXISTS ${picture} OR NOT so MATCHES "1265 scans")
  message(FATAL_ERROR "dispel render failed (${rc}): ${so}${se}")
endif()
file(READ ${picture} png_header LIMIT 8 HEX)
if(NOT png_header STREQUAL "89504e470d0a1a0a")
  message(FATAL_ERROR "dispel render wrote no PNG: ${png_header}")
endif()
file(REMOVE ${picture})
expect_error_no_output("unknown view 'top'" ${picture}
                       render ${BAG} -o ${picture} --static-sensor --view top)
expect_error_no_output("scan index 5000 out of range" ${picture}
                       render ${BAG} -o ${picture} --static-sensor --view scan --scan-index 5000)
expect_error_no_output("no nav_msgs/Odometry topic /odom" ${picture} render ${BAG} -o ${picture})
# dispel eval --plot: the evaluation of the short simulated run above as a picture.
file(REMOVE ${WORK_DIR}/eval.png)
run_dispel(rc so se eval --truth ${sim} --result ${WORK_DIR}/sim_filtered.bag --plot
           ${WORK_DIR}/eval.png)
if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK_DIR}/eval.png OR NOT so MATCHES "preservation rate")
  message(FATAL_ERROR "dispel eval --plot failed (${rc}): ${so}${se}")
endif()
expect_error_no_output("unknown picture format" ${WORK_DIR}/eval.gif
                       eval --truth ${sim} --result ${WORK_DIR}/sim_filtered.bag
                       --plot ${WORK_DIR}/eval.gif)
message(STATUS "dispel render contract holds")

# Issue 16: write errors, outputs that would destroy inputs, files that are not files, numbers
# that are not finite, unbounded echoes. Each: one line naming the problem, the exit code, no
# output and no OUT.partial, all before any work where the command line already tells.
function(expect_refused code expected output)
  if(NOT output MATCHES "^/dev/")  # Never remove a device (the test may run as root).
    file(REMOVE ${output} ${output}.partial)
  endif()
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE so ERROR_VARIABLE se
                  TIMEOUT 120)
  string(STRIP "${se}" line)
  string(LENGTH "${line}" length)
  if(NOT rc STREQUAL "${code}" OR NOT line MATCHES "${expected}" OR line MATCHES "\n"
     OR length GREATER 500 OR EXISTS ${output}.partial)
    message(FATAL_ERROR "'${ARGN}': expected exit ${code} and one line matching '${expected}' "
                        "and no ${output}.partial; got ${rc}:\n${se}")
  endif()
  if(NOT output MATCHES "^/dev/" AND EXISTS ${output})
    message(FATAL_ERROR "'${ARGN}' left ${output}")
  endif()
endfunction()
# A file-size limit as a full disk would set it: 64 blocks of 512 or 1024 bytes.
set(limited sh -c "ulimit -f 64 && exec \"$@\"" limited)

# Item 4: /dev/full and a file-size limit, for filter, odom, sim and --stats.
expect_refused(1 "^dispel filter: /dev/full: cannot write .*No space left on device" /dev/full
               ${DISPEL} filter ${BAG} -o /dev/full --static-sensor)
expect_refused(1 "^dispel filter: .*out.bag: cannot write the bag .*File too large" ${out}
               ${limited} ${DISPEL} filter ${BAG} -o ${out} --static-sensor)
expect_refused(1 "^dispel odom: /dev/full: cannot write .No space left on device" /dev/full
               ${DISPEL} odom ${sim} -o /dev/full)
expect_refused(1 "^dispel odom: .*traj_limited.csv: cannot write .File too large" ${WORK_DIR}/traj_limited.csv
               ${limited} ${DISPEL} odom ${SOURCE_DIR}/data/robot_localization/test1.bag
               -o ${WORK_DIR}/traj_limited.csv --wheel-topic /husky_velocity_controller/odom)
expect_refused(1 "^dispel sim: /dev/full: cannot write .*No space left on device" /dev/full
               ${DISPEL} sim ${SOURCE_DIR}/config/scenarios/thesis_hall.yaml -o /dev/full
               --duration 4)
expect_refused(1 "^dispel sim: .*sim_limited.bag: cannot write the bag .*File too large"
               ${WORK_DIR}/sim_limited.bag ${limited} ${DISPEL} sim
               ${SOURCE_DIR}/config/scenarios/thesis_hall.yaml -o ${WORK_DIR}/sim_limited.bag
               --duration 30)
expect_refused(1 "^dispel filter: statistics not written: /dev/full: cannot write .No space left"
               /dev/full ${DISPEL} filter ${BAG} -o ${WORK_DIR}/stats_full.bag --static-sensor
               --stats /dev/full)
file(REMOVE ${WORK_DIR}/stats_full.bag)
# The bag to /dev/null (a device: no file-size limit), the statistics under a 1-block limit.
expect_refused(1 "^dispel filter: statistics not written: .*stats_limited.json: cannot write .File too large"
               ${WORK_DIR}/stats_limited.json sh -c "ulimit -f 1 && exec \"$@\"" limited ${DISPEL}
               filter ${BAG} -o /dev/null --static-sensor --stats ${WORK_DIR}/stats_limited.json)
message(STATUS "write errors: one line, exit 1, nothing left behind")

# Item 7: no output may be an input or another output; every output's directory exists; checked
# before any work (the bag of the --stats nodir/ case is never written).
expect_refused(1 "--stats '.*out.bag' and -o '.*out.bag' are the same file" ${out}
               ${DISPEL} filter ${BAG} -o ${out} --stats ${out} --static-sensor)
file(WRITE ${WORK_DIR}/in.log "# a CARMEN log that must survive\n")
expect_refused(1 "-o '.*in.log' is the same file as the input '.*in.log'; the input would be"
               /dev/null ${DISPEL} filter ${WORK_DIR}/in.log -o ${WORK_DIR}/../cli_test/in.log)
file(READ ${WORK_DIR}/in.log kept)
if(NOT kept STREQUAL "# a CARMEN log that must survive\n")
  message(FATAL_ERROR "filter in.log -o in.log changed in.log")
endif()
file(WRITE ${WORK_DIR}/w.csv "t,v_left,v_right\n0,1,1\n1,1,1\n")
expect_refused(1 "-o '.*w.csv' is the same file as the input --wheels-csv" /dev/null
               ${DISPEL} odom --wheels-csv ${WORK_DIR}/w.csv -o ${WORK_DIR}/w.csv)
expect_refused(1 "--truth-csv '.*t.csv' and -o '.*t.csv' are the same file" ${WORK_DIR}/t.csv
               ${DISPEL} odom ${sim} -o ${WORK_DIR}/t.csv --truth-csv ${WORK_DIR}/./t.csv)
expect_refused(1 "--stats '.*nodir/s.json': the directory '.*nodir' does not exist" ${out}
               ${DISPEL} filter ${BAG} -o ${out} --stats ${WORK_DIR}/nodir/s.json --static-sensor)
expect_refused(1 "--config '.*': not a regular file .a directory." ${out}
               ${DISPEL} filter ${BAG} -o ${out} --config ${WORK_DIR} --static-sensor)
execute_process(COMMAND mkfifo ${WORK_DIR}/fifo.yaml)
expect_refused(1 "--config '.*fifo.yaml': not a regular file .a FIFO." ${out}
               ${DISPEL} filter ${BAG} -o ${out} --config ${WORK_DIR}/fifo.yaml --static-sensor)
expect_refused(1 "^dispel sim: '.*fifo.yaml': not a regular file .a FIFO." ${WORK_DIR}/x.bag
               ${DISPEL} sim ${WORK_DIR}/fifo.yaml -o ${WORK_DIR}/x.bag)
file(WRITE ${WORK_DIR}/empty.yaml "")
expect_refused(1 "^dispel sim: .*empty.yaml: the scenario file is empty$" ${WORK_DIR}/x.bag
               ${DISPEL} sim ${WORK_DIR}/empty.yaml -o ${WORK_DIR}/x.bag)
file(WRITE ${WORK_DIR}/nan_wall.yaml "world: {walls: [[0, 0, .nan, 1]]}\n")
expect_refused(1 "world.walls.0..2. must be a finite number, got '.nan'" ${WORK_DIR}/x.bag
               ${DISPEL} sim ${WORK_DIR}/nan_wall.yaml -o ${WORK_DIR}/x.bag)
# Command-line errors: the usage exit code 2, one line, a readable bound.
expect_refused(2 "^dispel sim: --duration: must be a finite number > 0, got nan " ${WORK_DIR}/x.bag
               ${DISPEL} sim ${SOURCE_DIR}/config/scenarios/thesis_hall.yaml -o ${WORK_DIR}/x.bag
               --duration nan)
expect_refused(2 "^dispel sim: --duration: must be a finite number > 0, got -1 " ${WORK_DIR}/x.bag
               ${DISPEL} sim ${SOURCE_DIR}/config/scenarios/thesis_hall.yaml -o ${WORK_DIR}/x.bag
               --duration -1)
# dispel sim streams the run into the bag (memory does not grow with the duration), but a run
# whose bag would not fit on the disk is refused before any work: one line naming the duration
# and both sizes, exit 1, no output (a run of 1e9 s would take years: the timeout would show it).
string(TIMESTAMP before "%s")
expect_refused(1 "^dispel sim: --duration 1e\\+09 s would write a bag of about [0-9.]+ [PT]B, but '.*' has [0-9.]+ [a-zA-Z]+ free$"
               ${WORK_DIR}/x.bag ${DISPEL} sim ${SOURCE_DIR}/config/scenarios/thesis_hall.yaml
               -o ${WORK_DIR}/x.bag --duration 1e9)
string(TIMESTAMP after "%s")
math(EXPR took "${after} - ${before}")
if(took GREATER 10)
  message(FATAL_ERROR "dispel sim --duration 1e9 took ${took} s to be refused: it did work first")
endif()
expect_refused(2 "^dispel render: --from: 'inf' is not a finite number" ${WORK_DIR}/x.png
               ${DISPEL} render ${BAG} -o ${WORK_DIR}/x.png --from inf)
expect_refused(2 "^dispel filter: .*--output is required" ${out} ${DISPEL} filter ${BAG})
# An echoed input is cut (a 100 kB key would have been a 100 kB line).
string(REPEAT "k" 100000 long_value)
file(WRITE ${WORK_DIR}/long_key.yaml "segmentation:\n  cluster_gap_m: ${long_value}\n")
expect_refused(1 "cluster_gap_m must be a number, got 'kkkk.*'... .100000 bytes.$" ${out}
               ${DISPEL} filter ${BAG} -o ${out} --config ${WORK_DIR}/long_key.yaml --static-sensor)

# Ctrl-C during dispel sim: interrupted with nothing written, or done with a complete bag.
foreach(delay 0.3 1.0 2.0)
  set(sim_out ${WORK_DIR}/sim_interrupted.bag)
  file(REMOVE ${sim_out})
  execute_process(COMMAND timeout --preserve-status -s INT ${delay} ${DISPEL} sim
                          ${SOURCE_DIR}/config/scenarios/thesis_hall.yaml -o ${sim_out} --duration 600
                  RESULT_VARIABLE rc OUTPUT_VARIABLE so ERROR_VARIABLE se)
  if(EXISTS ${sim_out}.partial OR (rc EQUAL 130 AND EXISTS ${sim_out})
     OR NOT (rc EQUAL 130 OR rc EQUAL 0))
    message(FATAL_ERROR "dispel sim under SIGINT after ${delay} s: exit ${rc}, ${se}")
  endif()
endforeach()
message(STATUS "issue 16 contract holds")

# Issue 16 item 1: a CARMEN log whose time counts from 0 (as the classic corrected logs): filtered
# with its stamps shifted by 1 s (said on stderr), and the output renders.
set(carmen_out ${WORK_DIR}/carmen_from0.bag)
file(REMOVE ${carmen_out})
run_dispel(rc so se filter ${SOURCE_DIR}/data/carmen/leg_tracker_from0.log -o ${carmen_out}
           --stats ${WORK_DIR}/carmen_stats.json)
if(NOT rc EQUAL 0 OR NOT so MATCHES "100 scans" OR NOT se MATCHES "counts time from 0: every stamp is shifted by \\+1 s")
  message(FATAL_ERROR "dispel filter on a CARMEN log from time 0 failed (${rc}): ${so}${se}")
endif()
file(READ ${WORK_DIR}/carmen_stats.json carmen_stats)
string(JSON offset GET "${carmen_stats}" stamp_offset_s)
if(NOT offset EQUAL 1)
  message(FATAL_ERROR "stamp_offset_s ${offset}: ${carmen_stats}")
endif()
run_dispel(rc so se render ${carmen_out} -o ${WORK_DIR}/carmen.png --size 400x300)
if(NOT rc EQUAL 0 OR NOT so MATCHES "100 scans" OR NOT EXISTS ${WORK_DIR}/carmen.png)
  message(FATAL_ERROR "dispel render on a filtered CARMEN log failed (${rc}): ${so}${se}")
endif()
file(WRITE ${WORK_DIR}/wrapped.log "FLASER 3 1 1 1 0 0 0 0 0 0 5e9 host 0\n")
expect_refused(1 "wrapped.log: line 1 .FLASER.: ipc_timestamp '5e9' is not a time a recording can hold"
               ${out} ${DISPEL} filter ${WORK_DIR}/wrapped.log -o ${out})
message(STATUS "CARMEN logs from time 0 filter and render")

# Issue 16 item 2: a sparse log (scans 5 s apart) resets the filter at nearly every scan: a
# warning on stderr and scans.mostly_unfiltered in the statistics.
string(REPEAT "2 " 181 ranges)
set(sparse_log "")
foreach(k RANGE 1 20)
  math(EXPR t "5 * ${k}")
  string(APPEND sparse_log "FLASER 181 ${ranges}0 0 0 0 0 0 ${t} host ${t}\n")
endforeach()
file(WRITE ${WORK_DIR}/sparse.log "${sparse_log}")
run_dispel(rc so se filter ${WORK_DIR}/sparse.log -o ${WORK_DIR}/sparse.bag
           --stats ${WORK_DIR}/sparse.json)
file(READ ${WORK_DIR}/sparse.json sparse_stats)
string(JSON mostly GET "${sparse_stats}" scans mostly_unfiltered)
string(JSON reset GET "${sparse_stats}" scans reset)
if(NOT rc EQUAL 0 OR NOT se MATCHES "warning: 19 of 20 scans reset the filter .19 after a time gap"
   OR NOT mostly STREQUAL "ON" OR NOT reset EQUAL 19)
  message(FATAL_ERROR "sparse log: no warning or statistics (${rc}): ${se}\n${sparse_stats}")
endif()
message(STATUS "a sparse log is reported")

# Issue 16, item 3: a corrupt bag crashed dispel filter and odom (SIGSEGV in the bag library,
# OUT.bag.partial left behind) or made the bag library allocate without bound. The first index
# data record of a simulated bag: "op=\x04" is the third of its header fields (conn, count, op,
# ver), so its data length is 16 bytes after that and its first entry's time and offset 24.
run_dispel(rc so se sim ${SOURCE_DIR}/config/scenarios/empty_hall.yaml -o ${WORK_DIR}/hall.bag
           --duration 3)
file(READ ${WORK_DIR}/hall.bag hall HEX)
string(FIND "${hall}" "6f703d04" op_hex)
math(EXPR op_pos "${op_hex} / 2")
math(EXPR index_pos "${op_pos} - 35")
function(corrupt name at bytes)
  file(COPY_FILE ${WORK_DIR}/hall.bag ${WORK_DIR}/${name}.bag)
  execute_process(COMMAND sh -c "printf '${bytes}' | dd of=${WORK_DIR}/${name}.bag bs=1 seek=${at} conv=notrunc 2>/dev/null"
                  RESULT_VARIABLE rc)
endfunction()
math(EXPR at "${op_pos} + 24")
corrupt(entry ${at} "\\177\\177\\177\\177\\177\\177\\177\\177")
math(EXPR at "${op_pos} + 16")
corrupt(length ${at} "\\377\\377\\377\\177")
set(bad_entry "corrupt bag: record at byte ${index_pos}: index entry 0 points at byte 2139062143 of its chunk")
set(bad_length "corrupt bag: record at byte ${index_pos}: data of 2147483647 bytes runs past the end")
foreach(case entry length)
  expect_refused(1 "^dispel filter: .*${case}.bag: ${bad_${case}}" ${WORK_DIR}/corrupt_out.bag
                 ${DISPEL} filter ${WORK_DIR}/${case}.bag -o ${WORK_DIR}/corrupt_out.bag)
  expect_refused(1 "^dispel odom: .*${case}.bag: ${bad_${case}}" ${WORK_DIR}/corrupt_out.csv
                 ${DISPEL} odom ${WORK_DIR}/${case}.bag -o ${WORK_DIR}/corrupt_out.csv)
endforeach()
message(STATUS "a corrupt bag: one line naming the record, exit 1, nothing left behind")

# dispel clean: the cleaned recording and, per object, what decided whether it moved: found
# dynamic in moving_min_scans scans and, in them, travelled moving_min_travel_m.
set(cleaned ${WORK_DIR}/clean.bag)
file(REMOVE ${cleaned})
run_dispel(rc so se clean ${BAG} -o ${cleaned} --static-sensor --scale-to-scanner
           --stats ${WORK_DIR}/clean_stats.json)
if(NOT rc EQUAL 0 OR NOT EXISTS ${cleaned} OR NOT so MATCHES "1265 scans")
  message(FATAL_ERROR "dispel clean failed (${rc}): ${so} ${se}")
endif()
file(READ ${WORK_DIR}/clean_stats.json clean_stats)
string(JSON min_scans GET "${clean_stats}" config moving_min_scans)
string(JSON min_travel GET "${clean_stats}" config moving_min_travel_m)
string(JSON object_count LENGTH "${clean_stats}" objects)
# The beams removed add up over their reasons, legs at range (none in this still scene) included.
string(JSON removed_total GET "${clean_stats}" beams_removed total)
set(removed_sum 0)
foreach(reason online moved_later vacated walked_legs)
  string(JSON removed_by GET "${clean_stats}" beams_removed ${reason})
  math(EXPR removed_sum "${removed_sum} + ${removed_by}")
endforeach()
if(NOT removed_sum EQUAL removed_total OR removed_total LESS 10000)
  message(FATAL_ERROR "beams removed ${removed_total}, by reason ${removed_sum}: ${clean_stats}")
endif()
set(moved 0)
math(EXPR last "${object_count} - 1")
foreach(k RANGE ${last})
  string(JSON dynamic_scans GET "${clean_stats}" objects ${k} dynamic_scans)
  string(JSON dynamic_travel GET "${clean_stats}" objects ${k} dynamic_travel_m)
  string(JSON moving GET "${clean_stats}" objects ${k} moving)
  if(dynamic_scans GREATER_EQUAL min_scans AND NOT dynamic_travel LESS min_travel)
    set(expected ON)
  else()
    set(expected OFF)
  endif()
  if((moving AND NOT expected) OR (expected AND NOT moving))
    message(FATAL_ERROR "object ${k}: moving ${moving} with ${dynamic_scans} dynamic scans, "
                        "${dynamic_travel} m while dynamic: ${clean_stats}")
  endif()
  if(moving)
    math(EXPR moved "${moved} + 1")
  endif()
endforeach()
if(moved LESS 10)
  message(FATAL_ERROR "${moved} objects moved of the demo's walkers: ${clean_stats}")
endif()
# A still sensor's poses are exact: the seen-through rule is on (2 scans in a row) unless asked
# otherwise, and it removes what came and stood (beams vacated).
string(JSON through GET "${clean_stats}" config through_min_scans)
string(JSON exact GET "${clean_stats}" config poses_exact)
string(JSON vacated GET "${clean_stats}" beams_removed vacated)
if(NOT through EQUAL 2 OR NOT exact OR vacated LESS 1000)
  message(FATAL_ERROR "a still sensor: through_min_scans ${through}, poses_exact ${exact}, "
                      "${vacated} beams vacated: ${clean_stats}")
endif()
expect_refused(1 "^dispel clean: clean.through_min_scans must be 0 .off. or in .1, 10000., got -2"
               ${WORK_DIR}/clean_bad.bag ${DISPEL} clean ${BAG} -o ${WORK_DIR}/clean_bad.bag
               --static-sensor --through-scans -2)
expect_refused(1 "^dispel clean: clean.moving_min_travel_m must be in .0, 100., got -1"
               ${WORK_DIR}/clean_bad.bag ${DISPEL} clean ${BAG} -o ${WORK_DIR}/clean_bad.bag
               --static-sensor --moving-travel -1)
message(STATUS "dispel clean: objects moved by their dynamic scans and travel; a still sensor's "
               "places seen through; bad travel and scan counts refused")
