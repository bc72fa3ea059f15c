!> &linear (docs/input.md): the linearised state-space model of the run's configuration, and
!> its datasets in the result file (docs/output.md).
submodule (analysis_run) analysis_run_linear
  use model_system, only: NODE_SLOTS
  use dynamics_linear, only: linearise, linear_model_t
  use elements_base, only: MODE_DYNAMIC, MODE_RIGID, MODE_PRESCRIBED
  use reduction_basis, only: basis_spec_t, compute_basis, held_joints
  use model_scene, only: JOINTS_HELD
  implicit none

  !> Component names of inputs (forces, moments) and outputs (displacements, rotations):
  !> planar x, y, phi; spatial x, y, z and the rotations about x, y, z.
  character(len=6), parameter :: PLANAR_IN(3) = ['fx    ', 'fy    ', 'moment']
  character(len=6), parameter :: SPATIAL_IN(6) = ['fx', 'fy', 'fz', 'mx', 'my', 'mz']
  character(len=6), parameter :: PLANAR_OUT(3) = ['x  ', 'y  ', 'phi']
  character(len=6), parameter :: SPATIAL_OUT(6) = ['x ', 'y ', 'z ', 'rx', 'ry', 'rz']

contains

  module subroutine run_linear(this, err)
    type(run_t), intent(inout) :: this
    type(error_t), intent(out) :: err
    integer, allocatable :: inputs(:, :), outputs(:, :)
    type(basis_t) :: basis
    integer :: i, k
    associate (lin => this%scene%linear, spatial => this%dyn%model%dim == 3)
      if (spatial) then
        call components(this, lin%inputs, 'inputs', SPATIAL_IN, inputs, err)
        if (err%ok()) call components(this, lin%outputs, 'outputs', SPATIAL_OUT, outputs, err)
      else
        call components(this, lin%inputs, 'inputs', PLANAR_IN, inputs, err)
        if (err%ok()) call components(this, lin%outputs, 'outputs', PLANAR_OUT, outputs, err)
      end if
      if (.not. err%ok()) return
      this%dyn%kin%continuation = .true.
      if (.not. allocated(lin%times)) then
        allocate(this%linear(1))
        if (this%scene%reduction%active) then
          ! The reduced model the run will integrate, at its reference q_ref = q_static.
          call reduction_basis(this, this%dyn, basis, err)
          if (err%ok()) call linearise(this%dyn, lin%time, this%q_static, inputs, outputs, &
            lin%along_motion, this%linear(1), err, basis=basis%v)
        else
          call linearise(this%dyn, lin%time, this%q_static, inputs, outputs, &
            lin%along_motion, this%linear(1), err)
        end if
        ! The kinematics refuses a time too far along the motions: say which variable.
        if (.not. err%ok()) then
          if (index(err%message, 'kinematics: the coordinates jump') == 1) &
            call err%prefix('group &linear: variable ''time'': ')
        end if
      else
        call along_run()
        if (err%ok()) then
          allocate(this%linear(size(lin%times)))
          do i = 1, size(lin%times)
            ! The stored output sample nearest to the time asked for (its time is written).
            k = minloc(abs(this%time - lin%times(i)), 1)
            ! Two times of one sample would give the same model twice without a word.
            if (i > 1) then
              if (k == minloc(abs(this%time - lin%times(i - 1)), 1)) then
                call err%set(ERR_INPUT, 'group &linear: variable ''times'': entries ' // &
                  int_str(i - 1) // ' and ' // int_str(i) // ' (' // real_str(lin%times(i - 1)) &
                  // ', ' // real_str(lin%times(i)) // ' s) both pick the output sample at ' // &
                  real_str(this%time(k)) // ' s: give times at least output_dt apart')
                exit
              end if
            end if
            call linearise_sample(this, k, inputs, outputs, this%linear(i), err)
            if (.not. err%ok()) exit
          end do
          ! Back to the charts of the run's end, which its last state is in.
          if (.not. allocated(this%red)) &
            call this%dyn%use_charts(this%dyn%chart_hist(:, size(this%time)))
        end if
      end if
      this%dyn%kin%continuation = .false.
      if (.not. err%ok()) then
        call err%prefix('linearisation: ')
        return
      end if
      if (this%verbose) write(*, '(a,i0,a,i0,a,i0,a,i0,a)') 'linear: ', size(this%linear), &
        ' state-space model(s), ', size(this%linear(1)%a, 1), ' states, ', &
        size(this%linear(1)%b, 2), ' inputs, ', size(this%linear(1)%c, 1), ' outputs'
    end associate

  contains

    !> `times` needs a dynamic run that covers them.
    subroutine along_run()
      if (.not. this%scene%dynamic%active) then
        call err%set(ERR_INPUT, 'group &linear: variable ''times'' linearises along the ' // &
          'dynamic run, but the scene has no &dynamic')
      else if (any(this%scene%linear%times < this%time(1)) .or. &
          any(this%scene%linear%times > this%time(size(this%time)))) then
        call err%set(ERR_INPUT, 'group &linear: variable ''times'' must lie within the ' // &
          'dynamic run (0 to t_end)')
      end if
    end subroutine along_run
  end subroutine run_linear

  !> The model at output sample k of the dynamic run: the full model at its stored state, or
  !> the reduced one at q_ref + V eta, V eta' with the basis that sample is relative to (not
  !> the statically corrected output: the correction is no state of the reduced equations).
  subroutine linearise_sample(this, k, inputs, outputs, lin, err)
    type(run_t), intent(inout) :: this
    integer, intent(in) :: k, inputs(:, :), outputs(:, :)
    type(linear_model_t), intent(out) :: lin
    type(error_t), intent(out) :: err
    if (.not. allocated(this%red)) then
      ! q_hist(:, k) is in the charts of its time (a free rotation's moves along the run).
      call this%dyn%use_charts(this%dyn%chart_hist(:, k))
      call linearise(this%dyn, this%time(k), this%dyn%q_hist(:, k), inputs, outputs, &
        .true., lin, err, this%dyn%v_hist(:, k))
      return
    end if
    associate (b => this%red%bases(this%red%basis_of(k)), eta => this%red%eta_hist(:, k))
      call linearise(this%dyn, this%time(k), b%q_ref + matmul(b%v, eta), inputs, outputs, &
        .true., lin, err, matmul(b%v, this%red%eta_dot_hist(:, k)), basis=b%v)
    end associate
  end subroutine linearise_sample

  !> The basis of &reduction at the configuration it names (basis_time or basis_prescribed,
  !> deformed as q_static), with `dyn` (the reduced run's model or, for &linear, the run's).
  module subroutine reduction_basis(this, dyn, basis, err)
    type(run_t), intent(in) :: this
    type(dynamics_t), intent(inout) :: dyn
    type(basis_t), intent(out) :: basis
    type(error_t), intent(out) :: err
    type(basis_spec_t) :: spec
    associate (r => this%scene%reduction)
      spec%selection = r%selection
      spec%n_modes = r%n_modes
      spec%cutoff_hz = r%cutoff_hz
      spec%auto_factor = r%auto_factor
      spec%eigensolver = r%eigensolver
      if (r%joints == JOINTS_HELD) call held_joints(dyn%model, spec%held, err)
      if (.not. err%ok()) return
      if (allocated(r%basis_prescribed)) then
        if (size(r%basis_prescribed) /= dyn%model%n_rh) then
          call err%set(ERR_INPUT, 'group &reduction: variable ''basis_prescribed'' needs ' // &
            int_str(dyn%model%n_rh) // ' values, one per prescribed coordinate (' // &
            prescribed_names(dyn%model) // '), got ' // int_str(size(r%basis_prescribed)))
          return
        end if
      end if
      ! An unallocated basis_prescribed counts as absent: the motions at basis_time apply.
      call compute_basis(dyn, spec, r%basis_time, this%q_static, r%basis_prescribed, basis, &
        err)
      ! What failed at the basis configuration; a message naming its group (n_modes out of
      ! range) needs no second one.
      if (.not. err%ok() .and. index(err%message, 'group &') /= 1) call err%prefix( &
        'group &reduction: basis configuration (basis_time = ' // real_str(r%basis_time) // '): ')
    end associate
  end subroutine reduction_basis

  function prescribed_names(model) result(names)
    type(model_t), intent(in) :: model
    character(len=:), allocatable :: names
    integer :: i
    names = ''
    do i = 1, model%n_rh
      if (i > 1) names = names // ', '
      names = names // model%q_name(i)
    end do
  end function prescribed_names

  !> 'node.component' names as node coordinates plus the component number (the last dot
  !> splits: link nodes are named 'link.3').
  subroutine components(this, names, var, known, which, err)
    type(run_t), intent(in) :: this
    type(label_t), intent(in) :: names(:)
    character(len=*), intent(in) :: var, known(:)
    integer, allocatable, intent(out) :: which(:, :)
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: node, comp, where
    integer :: i, k, dot, in, nr
    allocate(which(NODE_SLOTS + 1, size(names)))
    nr = merge(5, 3, this%dyn%model%dim == 3)
    where = 'group &linear: variable ''' // var // ''': '
    do i = 1, size(names)
      dot = index(names(i)%s, '.', back=.true.)
      node = names(i)%s(1:max(dot - 1, 0))
      comp = names(i)%s(dot + 1:)
      if (dot > 1 .and. is_mode_name(comp)) then
        ! A deformation mode of an element, or its stress: 'arm#1.e2', 'arm#1.sigma2'.
        call element_mode(this, node, comp, var, which(:, i), err)
        if (.not. err%ok()) return
        cycle
      end if
      in = 0
      if (dot > 1) in = this%dyn%model%find_node(node)
      if (in == 0 .and. dot > 1) then
        ! A hinge's 'label.torque' (input) or 'label.angle' (output) of its dynamic angle, or
        ! a truss's 'label.force' or 'label.elongation'.
        call joint_coordinate(this, node, comp, var, which(:, i), err)
        if (.not. err%ok()) return
        if (which(1, i) > 0) cycle
      end if
      if (in == 0) then
        call err%set(ERR_INPUT, where // '''' // names(i)%s // ''' is not node.component ' // &
          'with a node of the model')
        return
      end if
      k = findloc([(trim(known(k)) == comp, k = 1, size(known))], .true., 1)
      if (k == 0) then
        call err%set(ERR_INPUT, where // '''' // names(i)%s // ''': component ''' // comp // &
          ''' is not one of ' // join(known))
        return
      end if
      which(1:NODE_SLOTS, i) = this%dyn%model%node_coord(:, in)
      which(NODE_SLOTS + 1, i) = k
      if (k > 3 .or. (nr == 3 .and. k == 3)) then
        if (which(nr, i) == 0) then
          call err%set(ERR_INPUT, where // '''' // names(i)%s // ''': node ''' // node // &
            ''' has no rotation')
          return
        end if
      end if
    end do
  end subroutine components

  !> The dynamic coordinate of a hinge's angle or a truss's elongation, for the component
  !> 'torque' / 'force' (an input) or 'angle' / 'elongation' (an output): which = (index in
  !> q_dy, 0, ..., 0). which(1) = 0 when `label` is no hinge or truss; an error when it is one
  !> but the component or its mode class does not fit.
  subroutine joint_coordinate(this, label, comp, var, which, err)
    type(run_t), intent(in) :: this
    character(len=*), intent(in) :: label, comp, var
    integer, intent(out) :: which(:)
    type(error_t), intent(inout) :: err
    character(len=10) :: want
    character(len=:), allocatable :: kind
    integer :: iel, h
    which = 0
    if (any([(this%scene%hinges(h)%label == label, h = 1, size(this%scene%hinges))])) then
      kind = 'hinge'
      want = merge('torque    ', 'angle     ', var == 'inputs')
    else if (any([(this%scene%trusses(h)%label == label, h = 1, &
                   size(this%scene%trusses))])) then
      kind = 'truss'
      want = merge('force     ', 'elongation', var == 'inputs')
    else
      return
    end if
    associate (m => this%dyn%model)
      do iel = 1, m%n_elements
        if (m%elements(iel)%e%label /= label) cycle
        if (comp /= trim(want)) then
          call err%set(ERR_INPUT, 'group &linear: variable ''' // var // ''': ''' // label // &
            '.' // comp // ''': a ' // kind // '''s ' // var // ' component is ''' // &
            trim(want) // '''')
        else if (m%modes(m%mode_first(iel))%class /= MODE_DYNAMIC) then
          call err%set(ERR_INPUT, 'group &linear: variable ''' // var // ''': ' // kind // &
            ' ''' // label // ''' is not dynamic (its mode is no degree of freedom)')
        else
          which(1) = m%modes(m%mode_first(iel))%q - m%n_rh
        end if
        return
      end do
    end associate
  end subroutine joint_coordinate

  !> 'e' or 'sigma' followed by digits only: a mode component (no node component looks so).
  pure logical function is_mode_name(comp)
    character(len=*), intent(in) :: comp
    integer :: start
    start = 0
    if (index(comp, 'e') == 1) start = 2
    if (index(comp, 'sigma') == 1) start = 6
    if (start > len(comp)) start = 0
    is_mode_name = start > 0
    if (is_mode_name) is_mode_name = verify(comp(start:), '0123456789') == 0
  end function is_mode_name

  !> Element `label`'s mode 'e<j>' (its deformation e_j) or 'sigma<j>' (its stress resultant
  !> (S e)_j) as an output: which = (element, j, 1 for the stress else 0, 0, 0, -1), the -1
  !> in the component slot telling dynamics_linear's component_rows so.
  subroutine element_mode(this, label, comp, var, which, err)
    type(run_t), intent(in) :: this
    character(len=*), intent(in) :: label, comp, var
    integer, intent(out) :: which(:)
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: where
    integer :: iel, j, digits, ios
    logical :: stress
    which = 0
    where = 'group &linear: variable ''' // var // ''': ''' // label // '.' // comp // ''': '
    if (var == 'inputs') then
      call err%set(ERR_INPUT, where // 'a deformation mode or stress is an output only ' // &
        '(inputs are node forces and moments or hinge torques)')
      return
    end if
    stress = comp(1:1) == 's'
    digits = merge(6, 2, stress)
    iel = 0
    do j = 1, this%dyn%model%n_elements
      if (this%dyn%model%elements(j)%e%label == label) iel = j
    end do
    if (iel == 0) then
      call err%set(ERR_INPUT, where // 'no element is labelled ''' // label // ''' (beams ' // &
        'are ''link#k'', k = 1 .. n_elements, hinges, trusses and sliders their label; ' // &
        'see /model/elements/label)')
      return
    end if
    associate (el => this%dyn%model%elements(iel)%e)
      ! Too many digits for an integer is out of range as well.
      read(comp(digits:), *, iostat=ios) j
      if (ios /= 0 .or. j < 1 .or. j > el%n_modes()) then
        call err%set(ERR_INPUT, where // 'element ''' // label // ''' (' // el%type_name() // &
          ') has modes 1 to ' // int_str(el%n_modes()))
        return
      end if
      ! The force a rigid or prescribed mode carries is the multiplier of its kinematic
      ! condition, not S e (which is zero there): the output would read 0 whatever the load.
      if (stress .and. (el%mode_class(j) == MODE_RIGID .or. &
          el%mode_class(j) == MODE_PRESCRIBED)) then
        call err%set(ERR_INPUT, where // 'mode ' // int_str(j) // ' of ''' // label // &
          ''' is ' // trim(merge('rigid     ', 'prescribed', el%mode_class(j) == MODE_RIGID)) &
          // ': the force it carries is a constraint force, not (S e)_' // int_str(j) // &
          ' (always 0); make the mode dynamic or elastic to output its stress')
        return
      end if
    end associate
    which(1:3) = [iel, j, merge(1, 0, stress)]
    which(size(which)) = -1
  end subroutine element_mode

  pure function join(words) result(s)
    character(len=*), intent(in) :: words(:)
    character(len=:), allocatable :: s
    integer :: i
    s = trim(words(1))
    do i = 2, size(words)
      s = s // ', ' // trim(words(i))
    end do
  end function join

  !> /linear: time (n_lin), A (n_lin, n_z, n_z), B (n_lin, n_z, n_u), C (n_lin, n_y, n_z),
  !> D (n_lin, n_y, n_u) and the names of the inputs and outputs.
  module subroutine write_linear(this, h5, err)
    type(run_t), intent(in) :: this
    type(h5_writer_t), intent(inout) :: h5
    type(error_t), intent(inout) :: err
    integer :: i
    call h5%write_real_1d('/linear/time', [(this%linear(i)%time, i = 1, size(this%linear))], &
      err, units='s')
    do i = 1, 4
      if (err%ok()) call h5%write_real_3d('/linear/' // 'ABCD'(i:i), &
        stacked(this%linear, i), err)
    end do
    if (err%ok()) call h5%write_string_1d('/linear/inputs', padded(this%scene%linear%inputs), &
      err)
    if (err%ok()) call h5%write_string_1d('/linear/outputs', &
      padded(this%scene%linear%outputs), err)
    ! The state z = (eta, eta') of a reduced model: k reduced coordinates instead of q_dy.
    if (err%ok()) call h5%write_string_attr('/linear', 'reduced', &
      trim(merge('yes', 'no ', this%linear(1)%k_reduced > 0)), err)
    if (err%ok()) call h5%write_int_attr('/linear', 'n_modes', this%linear(1)%k_reduced, err)

  end subroutine write_linear

  !> Matrix `which` (1 A, 2 B, 3 C, 4 D) of every model, each transposed: HDF5 shows a Fortran
  !> array's dimensions reversed, so (n_lin, rows, columns) reads as written.
  function stacked(models, which) result(stack)
    type(linear_model_t), intent(in) :: models(:)
    integer, intent(in) :: which
    real(wp), allocatable :: stack(:, :, :)
    integer :: k
    do k = 1, size(models)
      select case (which)
      case (1); call put(models(k)%a)
      case (2); call put(models(k)%b)
      case (3); call put(models(k)%c)
      case default; call put(models(k)%d)
      end select
    end do
  contains
    subroutine put(m)
      real(wp), intent(in) :: m(:, :)
      if (.not. allocated(stack)) allocate(stack(size(m, 2), size(m, 1), size(models)))
      stack(:, :, k) = transpose(m)
    end subroutine put
  end function stacked

  !> Labels as one blank-padded character array (the writer trims them again).
  pure function padded(labels) result(names)
    type(label_t), intent(in) :: labels(:)
    character(len=:), allocatable :: names(:)
    integer :: i, n
    n = 1
    do i = 1, size(labels)
      n = max(n, len(labels(i)%s))
    end do
    allocate(character(len=n) :: names(size(labels)))
    do i = 1, size(labels)
      names(i) = labels(i)%s
    end do
  end function padded
end submodule analysis_run_linear
