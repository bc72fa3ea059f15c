!> Scene text and model set-up shared by the test programs: numbers written into namelist
!> text, the source directory (for input/ files) and a dynamics_t built from scene text or
!> from a parsed namelist file.
module test_scenes
  use core_kinds, only: wp
  use core_error, only: error_t
  use io_namelist, only: nml_file_t
  use io_scene, only: read_scene
  use model_scene, only: scene_t
  use model_build, only: build_model
  use model_system, only: model_t
  use dynamics_system, only: dynamics_t
  use analysis_run, only: run_t
  implicit none
  private
  public :: rtxt, itxt, source_dir, make_dynamics, make_dynamics_from, run_to_file, &
    node_distance

contains

  !> A real as namelist text, to full precision.
  function rtxt(v) result(s)
    real(wp), intent(in) :: v
    character(len=:), allocatable :: s
    character(len=32) :: buf
    write(buf, '(es24.16e3)') v
    s = trim(adjustl(buf))
  end function rtxt

  !> An integer as namelist text.
  function itxt(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    character(len=16) :: buf
    write(buf, '(i0)') i
    s = trim(buf)
  end function itxt

  !> $FLEXMOR_SOURCE_DIR, or '.' when it is not set.
  function source_dir() result(dir)
    character(len=:), allocatable :: dir
    character(len=1024) :: buf
    integer :: n, stat
    call get_environment_variable('FLEXMOR_SOURCE_DIR', buf, n, stat)
    if (stat == 0 .and. n > 0) then
      dir = trim(buf)
    else
      dir = '.'
    end if
  end function source_dir

  !> Read the scene of a parsed file, build the model and initialise at (t = 0, q0);
  !> q0 = 0 if absent.
  subroutine make_dynamics_from(f, scene, dyn, err, q0)
    type(nml_file_t), intent(inout) :: f
    type(scene_t), intent(out) :: scene
    type(dynamics_t), intent(out) :: dyn
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: q0(:)
    type(model_t) :: model
    real(wp), allocatable :: q(:)
    call read_scene(f, scene, err)
    if (err%ok()) call build_model(scene, model, err)
    if (.not. err%ok()) return
    allocate(q(model%n_dy))
    q = 0.0_wp
    if (present(q0)) q = q0
    call dyn%init(model, 0.0_wp, q, err, scene%linear_solver)
  end subroutine make_dynamics_from

  !> Parse scene text, then as make_dynamics_from.
  subroutine make_dynamics(text, scene, dyn, err, q0)
    character(len=*), intent(in) :: text
    type(scene_t), intent(out) :: scene
    type(dynamics_t), intent(out) :: dyn
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: q0(:)
    type(nml_file_t) :: f
    call f%parse(text, 'test', err)
    if (err%ok()) call make_dynamics_from(f, scene, dyn, err, q0)
  end subroutine make_dynamics

  !> Run scene `text` (called `name` in messages) quietly and write its result file `path`.
  subroutine run_to_file(text, name, path, run, err)
    character(len=*), intent(in) :: text, name, path
    type(run_t), intent(inout) :: run
    type(error_t), intent(out) :: err
    run%verbose = .false.
    call run%load_text(text, name, err)
    if (err%ok()) call run%execute(err)
    if (err%ok()) call run%write(path, err)
  end subroutine run_to_file

  !> Largest distance [m] between a node's planar paths in two runs of one model.
  real(wp) function node_distance(a, b, label) result(d)
    type(run_t), intent(in) :: a, b
    character(len=*), intent(in) :: label
    integer :: ic(3)
    ic = a%dyn%model%node_coord(1:3, a%dyn%model%find_node(label))
    d = maxval(hypot(a%dyn%x_hist(ic(1), :) - b%dyn%x_hist(ic(1), :), &
                     a%dyn%x_hist(ic(2), :) - b%dyn%x_hist(ic(2), :)))
  end function node_distance
end module test_scenes
