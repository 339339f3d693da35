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
