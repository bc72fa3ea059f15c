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
  use integrators_system, only: bdf_order, INTEGRATOR_NAMES, INTEGRATOR_BDF, INTEGRATOR_GALPHA
  use core_error, only: ERR_INTERNAL
  implicit none

contains

  module procedure run_error_check
    character(len=10), parameter :: SOURCE(4) = [character(len=10) :: '', 'time steps', &
      'modes', 'mesh']
    type(run_t) :: rerun
    type(nml_file_t) :: file
    integer :: i, node, rotated
    real(wp) :: cpu0, cpu1, far, turned
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
    allocate(this%check_distance(size(this%time)), this%check_rotation(size(this%time)))
    far = -1.0_wp
    turned = -1.0_wp
    this%check_rotation_node = ''
    do i = 1, size(this%time)
      call compare_nodes(this, rerun, i, this%check_distance(i), node, &
        this%check_rotation(i), rotated)
      if (this%check_distance(i) > far) then
        far = this%check_distance(i)
        this%check_node = trim(this%dyn%model%node_label(node))
      end if
      if (rotated > 0 .and. this%check_rotation(i) > turned) then
        turned = this%check_rotation(i)
        this%check_rotation_node = trim(this%dyn%model%node_label(rotated))
      end if
    end do
    ! No node with a rotation of its own in both runs: nothing to report.
    if (len(this%check_rotation_node) == 0) deallocate(this%check_rotation)
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
      if (allocated(this%check_rotation)) then
        i = maxloc(this%check_rotation, 1)
        write(*, '(a)') 'error check: their rotations differ by up to ' // &
          approx_str(this%check_rotation(i)) // ' rad (node ''' // this%check_rotation_node // &
          ''', t = ' // approx_str(this%time(i)) // ' s)'
      end if
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
      if (err%ok()) call file%groups(ig)%set_raw('integrator', '''' // &
        trim(INTEGRATOR_NAMES(d%integrator)) // '''', err)
      if (.not. err%ok()) return
      select case (d%error_check)
      case (ERROR_CHECK_TOLERANCE)
        if (d%integrator == INTEGRATOR_GALPHA) then
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
          if (err%ok() .and. d%integrator == INTEGRATOR_BDF) call file%groups(ig)%set_raw( &
            'max_order', int_str(bdf_order(d%max_order, d%rtol)), err)
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

  !> At output t: the largest distance d of a node of this run from the second run's, and the
  !> largest angle between a node's orientations in the two runs (-1 and rotated = 0 where no
  !> node has a rotation of its own in both), with those nodes (indices of this run's model):
  !> every node, or with 'mesh' the &node points (the links' own points are elsewhere in the
  !> refined mesh).
  subroutine compare_nodes(this, rerun, t, d, node, angle, rotated)
    type(run_t), intent(in) :: this, rerun
    integer, intent(in) :: t
    real(wp), intent(out) :: d, angle
    integer, intent(out) :: node, rotated
    integer :: i, a, b
    real(wp) :: s
    d = -1.0_wp
    node = 1
    angle = -1.0_wp
    rotated = 0
    do i = 1, n_compared(this)
      if (this%scene%dynamic%error_check == ERROR_CHECK_MESH) then
        a = this%dyn%model%find_node(this%scene%nodes(i)%label)
        b = rerun%dyn%model%find_node(this%scene%nodes(i)%label)
      else
        a = i
        b = i
      end if
      s = distance_apart(this%dyn%model%node_coord(:, a), this%dyn%x_hist(:, t), &
        rerun%dyn%model%node_coord(:, b), rerun%dyn%x_hist(:, t))
      if (s > d) then
        d = s
        node = a
      end if
      s = angle_apart(this%dyn%model%node_coord(:, a), this%dyn%x_hist(:, t), &
        rerun%dyn%model%node_coord(:, b), rerun%dyn%x_hist(:, t))
      if (s > angle) then
        angle = s
        rotated = a
      end if
    end do
  end subroutine compare_nodes

  !> How many nodes compare_nodes visits: every node, or with 'mesh' the &node points.
  integer function n_compared(this)
    type(run_t), intent(in) :: this
    if (this%scene%dynamic%error_check == ERROR_CHECK_MESH) then
      n_compared = size(this%scene%nodes)
    else
      n_compared = size(this%dyn%model%node_coord, 2)
    end if
  end function n_compared

  !> The distance of a node at x_a (its coordinate slots ca, model_t%node_coord) from one at
  !> x_b (slots cb).
  pure real(wp) function distance_apart(ca, xa, cb, xb) result(d)
    integer, intent(in) :: ca(:), cb(:)
    real(wp), intent(in) :: xa(:), xb(:)
    integer, parameter :: SLOT(3) = [1, 2, 4]
    integer :: k
    d = 0.0_wp
    do k = 1, 3
      if (ca(SLOT(k)) > 0 .and. cb(SLOT(k)) > 0) d = d + (xa(ca(SLOT(k))) - xb(cb(SLOT(k))))**2
    end do
    d = sqrt(d)
  end function distance_apart

  !> The angle of the rotation that takes a node's orientation at x_a to the one at x_b (slots
  !> as distance_apart), -1 where either has no rotation of its own. Planar: the difference of
  !> the angles (a whole turn counts: the runs' angles are continuous in time); spatial: the
  !> angle of the relative rotation of the Euler parameters, in [0, pi], as an atan2 of the
  !> product's vector and scalar parts (accurate for small angles, where an acos is not).
  pure real(wp) function angle_apart(ca, xa, cb, xb) result(angle)
    integer, intent(in) :: ca(:), cb(:)
    real(wp), intent(in) :: xa(:), xb(:)
    real(wp) :: p(4), q(4), v(3)
    angle = -1.0_wp
    if (ca(3) > 0 .and. cb(3) > 0) then
      angle = abs(xa(ca(3)) - xb(cb(3)))
    else if (ca(5) > 0 .and. cb(5) > 0) then
      p = xa(ca(5):ca(5) + 3)
      q = xb(cb(5):cb(5) + 3)
      v = p(1) * q(2:4) - q(1) * p(2:4) - [p(3) * q(4) - p(4) * q(3), &
        p(4) * q(2) - p(2) * q(4), p(2) * q(3) - p(3) * q(2)]
      angle = 2.0_wp * atan2(norm2(v), abs(dot_product(p, q)))
    end if
  end function angle_apart
end submodule analysis_run_check
