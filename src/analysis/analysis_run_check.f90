!> &dynamic error_check: the global error of a dynamic run, measured by a second run of the same
!> scene that is more accurate in one respect (docs/theory.md section 6.2): its
!> tolerances (or fixed step) divided by error_check_factor, error_check_modes more modes in a
!> reduced run, or every link's elements split in two. The distance of the two runs' nodes at
!> each output time (with 'mesh' the &node points, which both meshes have) estimates the first
!> run's error from that source, accumulated along the whole run (the integrators' and the
!> reduction's own estimates are local).
submodule (analysis_run) analysis_run_check
  use model_scene, only: ERROR_CHECK_TOLERANCE, ERROR_CHECK_MODES, ERROR_CHECK_MESH, &
    ERROR_CHECK_NAMES
  use integrators_system, only: bdf_order
  use core_error, only: ERR_INTERNAL
  implicit none

contains

  module procedure run_error_check
    character(len=10), parameter :: SOURCE(4) = [character(len=10) :: '', 'time steps', &
      'modes', 'mesh']
    type(run_t) :: rerun
    type(nml_file_t) :: file
    integer :: i, node
    real(wp) :: cpu0, cpu1, far
    call cpu_time(cpu0)
    file = this%file
    call check_settings(this, file, this%check_rerun, err)
    if (.not. err%ok()) return
    if (this%verbose) then
      write(*, '(a)') 'error check: a second run with ' // this%check_rerun
      flush(output_unit)
    end if
    rerun%verbose = .false.
    rerun%progress_lines = this%verbose
    rerun%progress_kind = 'check'
    rerun%progress%interval = this%progress%interval
    call rerun%load_parsed(file, err)
    if (err%ok()) call copy_user_laws(this, rerun, err)
    if (err%ok()) then
      ! Only the dynamic run (from the same static state) is compared.
      rerun%scene%modal%active = .false.
      rerun%scene%buckling%active = .false.
      rerun%scene%linear%active = .false.
      call rerun%execute(err)
    end if
    if (.not. err%ok()) then
      err%message = 'error check (the second run, with ' // this%check_rerun // '): ' // &
        err%message
      return
    end if
    if (size(rerun%time) /= size(this%time) .or. .not. allocated(rerun%dyn%x_hist)) then
      call err%set(ERR_INTERNAL, 'error check: the second run has other output times')
      return
    end if
    allocate(this%check_distance(size(this%time)))
    far = -1.0_wp
    do i = 1, size(this%time)
      call farthest_node(this, rerun, i, this%check_distance(i), node)
      if (this%check_distance(i) > far) then
        far = this%check_distance(i)
        this%check_node = trim(this%dyn%model%node_label(node))
      end if
    end do
    this%check_steps = int(min(rerun%stats%n_steps, int(huge(1), i8)))
    call cpu_time(cpu1)
    this%check_cpu_s = cpu1 - cpu0
    if (this%verbose) then
      i = maxloc(this%check_distance, 1)
      write(*, '(a)') 'error check: the nodes of the two runs are up to ' // &
        approx_str(this%check_distance(i)) // ' m apart (node ''' // this%check_node // &
        ''', t = ' // approx_str(this%time(i)) // ' s): about the error of this run from its ' // &
        trim(SOURCE(this%scene%dynamic%error_check)) // &
        ' (the second run: ' // int_str(this%check_steps) // ' steps, ' // &
        approx_str(this%check_cpu_s) // ' s)'
    end if
  end procedure run_error_check

  !> The user control laws (&controller law = 'user') go to the second run as they are after
  !> the first (docs/input.md: a law's own data beyond its states x must not carry over
  !> between runs): a program's, which the second run's load cannot know, and a library's
  !> (that load attached its own already; the copy is the same law).
  subroutine copy_user_laws(this, rerun, err)
    type(run_t), intent(in) :: this
    type(run_t), intent(inout) :: rerun
    type(error_t), intent(inout) :: err
    integer :: k
    if (.not. allocated(this%dyn%model%controllers)) return
    do k = 1, size(this%dyn%model%controllers)
      associate (c => this%dyn%model%controllers(k))
        if (allocated(c%user_law)) call rerun%set_control_law(c%label, c%user_law, err)
        if (.not. err%ok()) return
      end associate
    end do
  end subroutine copy_user_laws

  !> The scene file of the second run (file, a copy of the run's) and its settings in words.
  !> The integrator is the one the run took (an 'auto' choice depends on rtol).
  subroutine check_settings(this, file, what, err)
    type(run_t), intent(in) :: this
    type(nml_file_t), intent(inout) :: file
    character(len=:), allocatable, intent(out) :: what
    type(error_t), intent(out) :: err
    integer :: ig, ir, k
    associate (d => this%scene%dynamic)
      ig = file%group_index('dynamic', 1)
      call file%groups(ig)%unset('error_check_factor')
      call file%groups(ig)%unset('error_check_modes')
      call file%groups(ig)%set_raw('error_check', '''none''', err)
      if (err%ok()) call file%groups(ig)%set_raw('integrator', '''' // d%integrator // &
        '''', err)
      if (.not. err%ok()) return
      select case (d%error_check)
      case (ERROR_CHECK_TOLERANCE)
        if (d%integrator == 'galpha') then
          what = 'dt ' // approx_str(d%dt / d%error_check_factor)
          call file%groups(ig)%set_raw('dt', real_str(d%dt / d%error_check_factor), err)
        else
          what = 'rtol ' // approx_str(d%rtol / d%error_check_factor) // ', atol ' // &
            approx_str(d%atol / d%error_check_factor)
          call file%groups(ig)%set_raw('rtol', real_str(d%rtol / d%error_check_factor), err)
          if (err%ok()) call file%groups(ig)%set_raw('atol', &
            real_str(d%atol / d%error_check_factor), err)
          ! BDF's order limit follows rtol when not given: keep this run's, so that only the
          ! tolerance differs (2 and 5 on either side of rtol 1e-5).
          if (err%ok() .and. d%integrator == 'bdf') call file%groups(ig)%set_raw('max_order', &
            int_str(bdf_order(d%max_order, d%rtol)), err)
        end if
      case (ERROR_CHECK_MODES)
        ir = file%group_index('reduction', 1)
        ! n_modes as given (with joints = 'held' the basis holds the joints' unit motions too),
        ! else the count cutoff_hz or auto_factor chose.
        k = this%initial_basis%k()
        if (this%scene%reduction%selection == 'count') k = this%scene%reduction%n_modes
        k = k + d%error_check_modes
        what = int_str(k) // ' modes'
        call file%groups(ir)%unset('cutoff_hz')
        call file%groups(ir)%unset('auto_factor')
        call file%groups(ir)%set_raw('n_modes', int_str(k), err)
      case (ERROR_CHECK_MESH)
        call refine_links(this, file, what, err)
      case default
        call err%set(ERR_INTERNAL, 'error check: unknown kind ' // &
          trim(ERROR_CHECK_NAMES(d%error_check)))
      end select
    end associate
  end subroutine check_settings
  !> Every &link with twice its elements: the &node points are where they were, every
  !> element is split at its middle (mesh_check_problem has refused the scenes where that
  !> changes the problem).
  subroutine refine_links(this, file, what, err)
    type(run_t), intent(in) :: this
    type(nml_file_t), intent(inout) :: file
    character(len=:), allocatable, intent(inout) :: what
    type(error_t), intent(inout) :: err
    integer :: i, total
    total = 0
    do i = 1, size(this%scene%links)
      associate (r => this%scene%links(i))
        call file%groups(file%group_index('link', i))%set_raw('n_elements', &
          int_str(2 * r%n_elements), err)
        if (.not. err%ok()) return
        total = total + 2 * r%n_elements
      end associate
    end do
    what = int_str(total) // ' beam elements (twice as many)'
  end subroutine refine_links

  !> Why the links of `scene` cannot be refined by error_check = 'mesh' ('' when they can):
  !> there are none, a controller measures or drives a link's own point ('link1.2' moves to
  !> where 'link1.4' was; masses, forces and joints sit at &node points, and the second run's
  !> output nodes are not compared), or a link lists its classes per element.
  module procedure mesh_check_problem
    character(len=*), parameter :: WHERE = 'group &dynamic: variable ''error_check'': ''mesh'' '
    integer :: i
    why = ''
    if (.not. allocated(scene%links)) then
      why = WHERE // 'refines the links, and the scene has no &link'
      return
    end if
    if (size(scene%links) == 0) then
      why = WHERE // 'refines the links, and the scene has no &link'
      return
    end if
    do i = 1, size(scene%links)
      associate (r => scene%links(i))
        if (len(controlled_point(scene, r%label)) > 0) then
          why = WHERE // 'halves every element, which moves the point ''' // &
            controlled_point(scene, r%label) // ''' of link ''' // r%label // &
            ''' that a &controller measures or drives: refine the mesh by hand'
        else if (many(r%elongation) .or. many(r%bending)) then
          why = WHERE // 'halves every element, and link ''' // r%label // &
            ''' lists its classes per element: give one class per link, or refine by hand'
        end if
        if (len(why) > 0) return
      end associate
    end do
  end procedure mesh_check_problem

  !> The first point of link `link` ('link.k') a controller measures or drives, or ''.
  function controlled_point(scene, link) result(point)
    type(scene_t), intent(in) :: scene
    character(len=*), intent(in) :: link
    character(len=:), allocatable :: point
    integer :: i, j
    point = ''
    if (.not. allocated(scene%controllers)) return
    do i = 1, size(scene%controllers)
      associate (c => scene%controllers(i))
        do j = 1, size(c%measure)
          if (on_link(c%measure(j)%s)) point = owner(c%measure(j)%s)
        end do
        do j = 1, size(c%actuator)
          if (on_link(c%actuator(j)%s)) point = owner(c%actuator(j)%s)
        end do
      end associate
      if (len(point) > 0) return
    end do
  contains
    logical function on_link(label)
      character(len=*), intent(in) :: label
      integer :: n
      n = len(link) + 1
      on_link = .false.
      if (len(label) > n) on_link = label(:n) == link // '.' .and. &
        verify(label(n + 1:n + 1), '0123456789') == 0
    end function on_link
    !> 'link.2' of 'link.2.y'.
    function owner(label) result(o)
      character(len=*), intent(in) :: label
      character(len=:), allocatable :: o
      o = label(:index(label, '.', back=.true.) - 1)
    end function owner
  end function controlled_point

  logical function many(classes)
    type(label_t), allocatable, intent(in) :: classes(:)
    many = .false.
    if (allocated(classes)) many = size(classes) > 1
  end function many

  !> The largest distance d of a node of this run from the second run's at output t, and that
  !> node (an index of this run's model): every node, or with 'mesh' the &node points (the
  !> links' own points are elsewhere in the refined mesh).
  subroutine farthest_node(this, rerun, t, d, node)
    type(run_t), intent(in) :: this, rerun
    integer, intent(in) :: t
    real(wp), intent(out) :: d
    integer, intent(out) :: node
    integer, parameter :: SLOT(3) = [1, 2, 4]
    real(wp), allocatable :: dx(:)
    integer :: i, k, a, b, ra, rb
    real(wp) :: s
    d = -1.0_wp
    node = 1
    if (this%scene%dynamic%error_check /= ERROR_CHECK_MESH) then
      dx = this%dyn%x_hist(:, t) - rerun%dyn%x_hist(:, t)
      do i = 1, size(this%dyn%model%node_coord, 2)
        s = this%dyn%model%translation(i, dx)
        if (s > d) then
          d = s
          node = i
        end if
      end do
      return
    end if
    do i = 1, size(this%scene%nodes)
      a = this%dyn%model%find_node(this%scene%nodes(i)%label)
      b = rerun%dyn%model%find_node(this%scene%nodes(i)%label)
      s = 0.0_wp
      do k = 1, 3
        ra = this%dyn%model%node_coord(SLOT(k), a)
        rb = rerun%dyn%model%node_coord(SLOT(k), b)
        if (ra > 0 .and. rb > 0) s = s + (this%dyn%x_hist(ra, t) - rerun%dyn%x_hist(rb, t))**2
      end do
      if (sqrt(s) > d) then
        d = sqrt(s)
        node = a
      end if
    end do
  end subroutine farthest_node
end submodule analysis_run_check
