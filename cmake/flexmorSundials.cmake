# The SUNDIALS targets flexmor links, and a workaround for Debian's SUNDIALS 6.4 packages,
# whose Fortran-module targets name a non-existent <prefix>/fortran include folder (the modules
# are in /usr/include/sundials/fortran). Used by the build and by the installed package config,
# because a downstream project links the same imported targets and needs the same fix.

set(FLEXMOR_SUNDIALS_TARGETS
    SUNDIALS::fcvode_mod_shared SUNDIALS::farkode_mod_shared SUNDIALS::fnvecserial_mod_shared
    SUNDIALS::fsunmatrixdense_mod_shared SUNDIALS::fsunlinsoldense_mod_shared
    SUNDIALS::cvode_shared SUNDIALS::arkode_shared SUNDIALS::nvecserial_shared
    SUNDIALS::sunmatrixdense_shared SUNDIALS::sunlinsoldense_shared)

# Replace every include folder ending in /fortran that does not exist by `moddir`; folders that
# exist (a SUNDIALS built from source) are kept, so the fix is a no-op there and idempotent.
function(flexmor_fix_sundials_fortran_includes moddir)
  foreach(tgt IN LISTS FLEXMOR_SUNDIALS_TARGETS)
    if(NOT TARGET ${tgt})
      continue()
    endif()
    get_target_property(incs ${tgt} INTERFACE_INCLUDE_DIRECTORIES)
    if(NOT incs)
      continue()
    endif()
    set(fixed "")
    foreach(dir IN LISTS incs)
      if(dir MATCHES "/fortran$" AND NOT EXISTS "${dir}" AND EXISTS "${moddir}")
        set(dir "${moddir}")
      endif()
      list(APPEND fixed "${dir}")
    endforeach()
    list(REMOVE_DUPLICATES fixed)
    set_target_properties(${tgt} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${fixed}")
  endforeach()
endfunction()
