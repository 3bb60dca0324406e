# cmake -DHELP2MAN=... -DPROGRAM=path [-DRUN=command] -DNAME=name -DVERSION=x.y.z -DSUMMARY=...
#       -DOUT=page.1.gz -DDOCDIR=... -DBUILD_RIGDIR=... -DINSTALL_RIGDIR=... -P man_page.cmake
# Writes a program's man page from its --help and --version, as installed: the
# program's name instead of its build path, and the installed rig folder in the
# defaults instead of the source tree's. RUN: what help2man runs, when not PROGRAM
# itself (a cross build's program under its emulator).
if(NOT RUN)
  set(RUN ${PROGRAM})
endif()
get_filename_component(out_dir ${OUT} DIRECTORY)
file(MAKE_DIRECTORY ${out_dir})
string(REGEX REPLACE "\\.gz$" "" page ${OUT})
# SEE ALSO: the other two programs, the per-command help and the documents.
set(others lightstage lightstage-domed lightstage-sim)
list(REMOVE_ITEM others ${NAME})
list(TRANSFORM others APPEND "(1)")
list(JOIN others ", " see_also)
set(include_file ${page}.include)
file(WRITE ${include_file} "[SEE ALSO]\n${see_also}.\n")
if(NAME STREQUAL "lightstage")
  file(APPEND ${include_file} ".PP\n\\fBlightstage\\fR \\fICOMMAND\\fR \\fB\\-\\-help\\fR describes a command.\n")
endif()
file(APPEND ${include_file} ".PP\nThe file formats, the protocol and the hardware: \\%${DOCDIR}.\n")
# --version-string: the programs' --version also lists their hardware backends,
# which would end up in the page.
execute_process(
  COMMAND ${HELP2MAN} --no-info --no-discard-stderr --name=${SUMMARY} --section=1
          --version-string=${VERSION} --include=${include_file} --output=${page} ${RUN}
  RESULT_VARIABLE status
  ERROR_VARIABLE errors)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "help2man ${PROGRAM} failed (${status}): ${errors}")
endif()
file(REMOVE ${include_file})
file(READ ${page} text)
string(REPLACE "${PROGRAM}" "${NAME}" text "${text}")
string(REPLACE "${RUN}" "${NAME}" text "${text}")
string(REPLACE "./${NAME}" "${NAME}" text "${text}")
# roff shows '-' as a hyphen; help2man escapes them, so the rig paths are matched escaped too.
string(REPLACE "-" "\\-" build_rigdir "${BUILD_RIGDIR}")
string(REPLACE "-" "\\-" install_rigdir "${INSTALL_RIGDIR}")
string(REPLACE "${build_rigdir}" "${install_rigdir}" text "${text}")
string(REPLACE "${BUILD_RIGDIR}" "${INSTALL_RIGDIR}" text "${text}")
file(WRITE ${page} "${text}")
# -n: no name or time stamp in the archive, so the page is the same on every build.
execute_process(COMMAND gzip -n -9 -f ${page} RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "gzip ${page} failed (${status})")
endif()
