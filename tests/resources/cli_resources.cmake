# The tool's resource and output probes (tests/resources/cli_resources.sh): outputs checked before
# the work, written through unique temporaries, never replacing a device or an input, removed on
# SIGTERM or at the next start; stdout write errors; threads; oversized headers; the memory limit;
# control bytes escaped, corrections checked against the keyframes, unmappable values refused;
# file names in text outputs (a 2D grid's YAML), empty keyframes, read-only outputs.
find_program(KNNOCC_BASH bash)
if(TARGET knnocc_tool AND KNNOCC_BASH)
  set(KNNOCC_RESOURCE_CASES
    missing_output_dir same_output_twice empty_output_name output_is_folder
    device_written_in_place user_tmp_untouched concurrent_writers stdout_full png_extension
    sim_non_empty_folder sigterm_removes_temporaries threads_capped huge_ply_header
    huge_pcd_header memory_far_rays memory_tiny_resolution memory_long_fine_rays memory_out_of_memory memory_broken_compressed memory_corrections
    memory_big_tree bad_memory_limit
    missing_input velodyne_without_calib utf8_bom_accepted mixed_ids_name_the_file info_like_map
    output_is_input control_bytes_escaped corrections_checked corrections_velodyne_frame
    corrections_key_range_note
    unmappable_values save_every_resumes stale_temporaries_removed
    corrections_outputs_all_or_none dangling_link_keeps_user_files heldout_repeated_id
    grid_yaml_names empty_keyframe_with_ids heldout_nothing_to_score errors_name_the_file
    read_only_output sigpipe_removes_temporaries stale_staging_folder_removed)
  foreach(_case IN LISTS KNNOCC_RESOURCE_CASES)
    add_test(NAME cli.resources.${_case}
      COMMAND "${KNNOCC_BASH}" "${CMAKE_CURRENT_LIST_DIR}/cli_resources.sh"
              "$<TARGET_FILE:knnocc_tool>" "${CMAKE_BINARY_DIR}/cli_resources" ${_case})
    set_tests_properties(cli.resources.${_case} PROPERTIES LABELS cli TIMEOUT 60
      FAIL_REGULAR_EXPRESSION "FAIL:" SKIP_REGULAR_EXPRESSION "SKIPPED:")
  endforeach()
  # Sanitizer builds set no address-space limit (it would break the shadow memory), so the
  # allocation failure the limit provokes cannot happen there.
  if(KNNOCC_SANITIZE)
    set_tests_properties(cli.resources.memory_out_of_memory cli.resources.memory_far_rays
      cli.resources.errors_name_the_file PROPERTIES ENVIRONMENT "KNNOCC_TOOL_SANITIZED=1")
  endif()
endif()
