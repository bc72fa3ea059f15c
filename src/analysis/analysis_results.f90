!> The results of one run, for programs that use flexmor as a library: output times, node
!> positions and rotations by label, modal frequencies, the static solution and the wall time,
!> copied out of a run_t so that callers need not know the model's internals. The same
!> quantities as the result file (docs/output.md), in memory.
module analysis_results
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use analysis_run, only: run_t
  implicit none
  private
  public :: results_t

  !> What a run computed. Arrays of an analysis the scene did not ask for have size 0.
  type :: results_t
    !> Output times of the dynamic analysis [s].
    real(wp), allocatable :: time(:)
    !> Load factor of each static step (load control: k / n_steps; arc-length: as traced).
    real(wp), allocatable :: load_factor(:)
    !> Dynamic (elastic) coordinates at the static equilibrium under the full load.
    real(wp), allocatable :: q_static(:)
    !> Natural frequencies of the modal analysis [Hz], ascending; negative: unstable mode.
    real(wp), allocatable :: frequency_hz(:)
    !> Labels of all nodes: the &node labels and the link-internal nodes ('link1.1', ...).
    character(len=64), allocatable :: node_label(:)
    !> Wall time of run%execute [s].
    real(wp) :: wall_time_s = 0.0_wp
    integer, allocatable, private :: node_coord(:, :)
    real(wp), allocatable, private :: x_static(:, :), x_dynamic(:, :)
  contains
    procedure :: from_run => results_from_run
    procedure :: has_node => results_has_node
    procedure :: node_position => results_node_position
    procedure :: node_rotation => results_node_rotation
  end type results_t

contains

  !> Copy the results out of a run after run%execute (the run itself is not changed).
  subroutine results_from_run(this, run)
    class(results_t), intent(out) :: this
    type(run_t), intent(in) :: run
    if (allocated(run%dyn%model%node_label)) then
      this%node_label = run%dyn%model%node_label
      this%node_coord = run%dyn%model%node_coord
    end if
    this%wall_time_s = run%wall_time_s
    allocate(this%time(0), this%load_factor(0), this%q_static(0), this%frequency_hz(0))
    if (run%scene%static%active .and. allocated(run%x_static)) then
      this%load_factor = run%static_load_factor
      this%q_static = run%q_static
      this%x_static = run%x_static
    end if
    if (run%scene%modal%active .and. allocated(run%modal%frequency_hz)) &
      this%frequency_hz = run%modal%frequency_hz
    if (run%scene%dynamic%active .and. allocated(run%time) .and. &
        allocated(run%dyn%x_hist)) then
      this%time = run%time
      this%x_dynamic = run%dyn%x_hist
    end if
  end subroutine results_from_run

  !> Whether `label` names a node of the model.
  logical function results_has_node(this, label)
    class(results_t), intent(in) :: this
    character(len=*), intent(in) :: label
    results_has_node = node_index(this, label) > 0
  end function results_has_node

  !> Position (x, y) [m] of node `label` at every output time (`analysis` = 'dynamic', shape
  !> (2, size(time))) or at every load step ('static', shape (2, size(load_factor))).
  subroutine results_node_position(this, label, analysis, pos, err)
    class(results_t), intent(in) :: this
    character(len=*), intent(in) :: label, analysis
    real(wp), allocatable, intent(out) :: pos(:, :)
    type(error_t), intent(out) :: err
    integer :: in
    call locate(this, label, analysis, in, err)
    if (.not. err%ok()) return
    ! x and y, and z in a spatial model.
    associate (rows => pack(this%node_coord([1, 2, 4], in), this%node_coord([1, 2, 4], in) > 0))
      if (analysis == 'static') then
        pos = this%x_static(rows, :)
      else
        pos = this%x_dynamic(rows, :)
      end if
    end associate
  end subroutine results_node_position

  !> Rotation [rad] of node `label` relative to the reference configuration, per output time
  !> ('dynamic') or load step ('static'); an error if the node has no rotation coordinate
  !> (a node of trusses or hinges only).
  subroutine results_node_rotation(this, label, analysis, rot, err)
    class(results_t), intent(in) :: this
    character(len=*), intent(in) :: label, analysis
    real(wp), allocatable, intent(out) :: rot(:)
    type(error_t), intent(out) :: err
    integer :: in, ic
    call locate(this, label, analysis, in, err)
    if (.not. err%ok()) return
    ic = this%node_coord(3, in)
    if (ic == 0) then
      call err%set(ERR_INPUT, 'results: node ''' // label // ''' has no rotation coordinate')
    else if (analysis == 'static') then
      rot = this%x_static(ic, :)
    else
      rot = this%x_dynamic(ic, :)
    end if
  end subroutine results_node_rotation

  !> The node's index, checking the label and that the analysis ran.
  subroutine locate(this, label, analysis, in, err)
    type(results_t), intent(in) :: this
    character(len=*), intent(in) :: label, analysis
    integer, intent(out) :: in
    type(error_t), intent(out) :: err
    in = node_index(this, label)
    if (in == 0) then
      call err%set(ERR_INPUT, 'results: no node ''' // label // '''')
    else if (analysis /= 'static' .and. analysis /= 'dynamic') then
      call err%set(ERR_INPUT, 'results: analysis ''' // analysis // &
        ''' is neither ''static'' nor ''dynamic''')
    else if (analysis == 'static' .and. .not. allocated(this%x_static)) then
      call err%set(ERR_INPUT, 'results: the run has no static analysis (group &static)')
    else if (analysis == 'dynamic' .and. .not. allocated(this%x_dynamic)) then
      call err%set(ERR_INPUT, 'results: the run has no dynamic analysis (group &dynamic)')
    end if
  end subroutine locate

  integer function node_index(this, label) result(in)
    type(results_t), intent(in) :: this
    character(len=*), intent(in) :: label
    integer :: i
    in = 0
    if (.not. allocated(this%node_label)) return
    do i = 1, size(this%node_label)
      if (this%node_label(i) == label) then
        in = i
        return
      end if
    end do
  end function node_index
end module analysis_results
