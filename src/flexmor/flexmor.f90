!> The public API of flexmor as a library: `use flexmor` is all a program needs.
!>
!> A run reads a scene (docs/input.md) from a file or from text, executes the analyses it asks
!> for, optionally writes the HDF5 result file (docs/output.md), and hands its results out as
!> a results_t:
!>
!>     use flexmor, only: wp, run_t, results_t, error_t
!>     type(run_t) :: run
!>     type(results_t) :: res
!>     type(error_t) :: err
!>     call run%load('scene.nml', err)        ! or run%load_text(text, 'name', err)
!>     if (err%ok()) call run%execute(err)
!>     if (err%ok()) call run%write('out.h5', err)
!>     call res%from_run(run)
!>     if (.not. err%ok()) print '(a)', err%message   ! err%code: ERR_INPUT, ...
!>
!> A &controller with law = 'user' gets its law from the program: extend control_law_t
!> (deferred evaluate, docs/api.md) and call run%set_control_law('label', law, err) between
!> load and execute. C programs use the same through include/flexmor.h (flexmor_c). A law
!> so set replaces the one a scene may name in a shared library (&controller library,
!> symbol), which load attaches.
!>
!> Library code never stops the program: every failure comes back as an error_t whose
!> message names the file, group and variable. With CMake: find_package(flexmor) and
!> target_link_libraries(app PRIVATE flexmor::flexmor).
module flexmor
  use core_kinds, only: wp, i8
  ! Fortran names are case-insensitive: the constant cannot keep its name beside the function.
  use core_version, only: VERSION_TEXT => FLEXMOR_VERSION
  use core_error, only: error_t, ERR_NONE, ERR_INPUT, ERR_MODEL, ERR_NUMERIC, ERR_IO, ERR_INTERNAL
  use analysis_run, only: run_t
  use analysis_results, only: results_t
  use model_control, only: control_law_t
  implicit none
  private
  public :: flexmor_version
  public :: wp, i8
  public :: error_t, ERR_NONE, ERR_INPUT, ERR_MODEL, ERR_NUMERIC, ERR_IO, ERR_INTERNAL
  public :: run_t, results_t, control_law_t

contains

  !> The version of the library, "major.minor.patch" (the file VERSION of the sources).
  function flexmor_version() result(version)
    character(len=:), allocatable :: version
    version = VERSION_TEXT
  end function flexmor_version
end module flexmor
