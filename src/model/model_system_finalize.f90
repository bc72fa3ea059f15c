!> Finishing a model: the checks of what a model built through the API must get right, the
!> numbering of coordinates, rows and q, and the counting condition with its message.
submodule (model_system) model_system_finalize
  implicit none

contains

  !> What a model built through the API must get right: dim 2 or 3, no z gravity in the
  !> plane, every moment on the four Euler parameters of one node, every actuator on a
  !> dynamic mode.
  subroutine check_consistency(this, err)
    type(model_t), intent(in) :: this
    type(error_t), intent(inout) :: err
    integer :: k, i
    if (this%dim /= 2 .and. this%dim /= 3) then
      call err%set(ERR_MODEL, 'model: dim must be 2 or 3, got ' // int_str(this%dim))
      return
    end if
    if (this%dim == 2 .and. this%gravity(3) /= 0) then
      call err%set(ERR_MODEL, 'model: gravity has a z component in a planar model (dim = 2)')
      return
    end if
    do k = 1, size(this%actuator_element)
      i = this%actuator_element(k)
      if (i < 1 .or. i > this%n_elements) then
        call err%set(ERR_MODEL, 'model: an actuator on element ' // int_str(i) // &
          ', which the model does not have')
        return
      end if
      if (this%modes(this%mode_first(i))%class /= MODE_DYNAMIC) then
        call err%set(ERR_MODEL, 'model: the actuator on ''' // this%elements(i)%e%label // &
          ''' drives a mode that is not dynamic (a driven joint''s angle must be a degree ' // &
          'of freedom)')
        return
      end if
    end do
    do k = 1, size(this%moment_lambda)
      i = this%moment_lambda(k)
      if (i < 1 .or. i + 3 > this%n_x) then
        call err%set(ERR_MODEL, 'model: moment on coordinates outside the model')
        return
      end if
      if (this%moment_motion(k) < 0 .or. this%moment_motion(k) > this%n_motions) then
        call err%set(ERR_MODEL, 'model: a moment follows motion ' // &
          int_str(this%moment_motion(k)) // ', which the model does not have')
        return
      end if
      if (any(this%coord_kind(i:i + 3) /= COORD_EULER)) then
        call err%set(ERR_MODEL, 'model: a moment acts on the four Euler parameters of a ' // &
          'node, but coordinate ''' // trim(this%coord_name(i)) // ''' starts no such four')
        return
      end if
    end do
  end subroutine check_consistency

  module procedure model_finalize
    integer :: i, m, n_rows, iq_rh, iq_dy
    logical :: calculable(this%n_x)
    if (.not. allocated(this%modes)) allocate(this%modes(0), this%mode_first(0))
    call check_consistency(this, err)
    if (.not. err%ok()) return
    calculable = .not. this%fixed .and. this%coord_input == 0
    allocate(this%calc_index(this%n_x))
    this%calc_index = 0
    this%n_c = 0
    do i = 1, this%n_x
      if (calculable(i)) then
        this%n_c = this%n_c + 1
        this%calc_index(i) = this%n_c
      end if
    end do
    this%calc_coord = pack([(i, i=1, this%n_x)], calculable)
    this%lumped_rows = pack([(i, i=1, this%n_x)], this%lumped > 0)
    this%n_rigid = count(this%modes%class == MODE_RIGID)
    this%n_elastic = count(this%modes%class == MODE_ELASTIC)
    this%n_rh = count(this%modes%class == MODE_PRESCRIBED) + count(this%coord_input == MODE_PRESCRIBED)
    this%n_dy = count(this%modes%class == MODE_DYNAMIC) + count(this%coord_input == MODE_DYNAMIC)
    this%n_q = this%n_rh + this%n_dy
    if (this%n_dy == 0) then
      call err%set(ERR_MODEL, 'the model has no dynamic deformation mode or coordinate: ' // &
        'nothing to compute')
      return
    end if
    n_rows = count(this%modes%class /= MODE_RELEASED .and. this%modes%class /= MODE_ELASTIC)
    if (n_rows /= this%n_c) then
      call err%set(ERR_MODEL, this%count_message(n_rows))
      return
    end if
    allocate(this%row_q(n_rows), this%q_mode(this%n_q), this%q_coord(this%n_q))
    allocate(this%q_motion(this%n_rh), this%input_q(this%n_x))
    this%q_mode = 0
    this%q_coord = 0
    this%input_q = 0
    n_rows = 0
    iq_rh = 0
    iq_dy = this%n_rh
    do m = 1, size(this%modes)
      associate (mode => this%modes(m))
        if (mode%class == MODE_RELEASED .or. mode%class == MODE_ELASTIC) cycle
        n_rows = n_rows + 1
        mode%row = n_rows
        this%row_q(n_rows) = 0
        if (mode%class == MODE_PRESCRIBED) then
          if (mode%motion < 1 .or. mode%motion > this%n_motions) then
            call err%set(ERR_INPUT, 'prescribed mode ' // this%mode_name(m) // ' has no motion')
            return
          end if
          iq_rh = iq_rh + 1
          mode%q = iq_rh
          this%q_motion(iq_rh) = mode%motion
        else if (mode%class == MODE_DYNAMIC) then
          iq_dy = iq_dy + 1
          mode%q = iq_dy
        end if
        if (mode%q > 0) then
          this%row_q(n_rows) = mode%q
          this%q_mode(mode%q) = m
        end if
      end associate
    end do
    do i = 1, this%n_x
      if (this%coord_input(i) == MODE_PRESCRIBED) then
        iq_rh = iq_rh + 1
        this%input_q(i) = iq_rh
        this%q_motion(iq_rh) = this%coord_motion(i)
      else if (this%coord_input(i) == MODE_DYNAMIC) then
        iq_dy = iq_dy + 1
        this%input_q(i) = iq_dy
      end if
      if (this%input_q(i) > 0) this%q_coord(this%input_q(i)) = i
    end do
    this%max_modes = 0
    this%max_dofs = 0
    do i = 1, this%n_elements
      this%max_modes = max(this%max_modes, this%elements(i)%e%n_modes())
      this%max_dofs = max(this%max_dofs, size(this%elements(i)%e%dofs))
    end do
    allocate(this%elastic_element(this%n_elements))
    do i = 1, this%n_elements
      this%elastic_element(i) = any(this%modes(this%mode_first(i):this%mode_first(i) + &
        this%elements(i)%e%n_modes() - 1)%class == MODE_ELASTIC)
    end do
    this%finalized = .true.
  end procedure model_finalize

  !> The counting condition of docs/input.md, with the numbers of each class.
  module procedure model_count_message
    character(len=400) :: buf
    integer :: n_rh_modes, n_dy_modes
    n_rh_modes = count(this%modes%class == MODE_PRESCRIBED)
    n_dy_modes = count(this%modes%class == MODE_DYNAMIC)
    write(buf, '(a,i0,a,i0,a,i0,a,i0,a,i0,a,i0,a)') 'the coordinate classes do not solve: ', &
      this%n_c, ' free nodal coordinates but ', n_rows, ' kinematic conditions (', &
      this%n_rigid, ' rigid + ', n_rh_modes, ' prescribed + ', n_dy_modes, &
      ' dynamic modes; ', this%n_elastic, ' elastic modes do not count)'
    msg = trim(buf)
    if (n_rows < this%n_c) then
      write(buf, '(a,i0,a)') '; the model is a mechanism: make ', this%n_c - n_rows, &
        ' more modes rigid, dynamic or prescribed (e.g. elastic -> dynamic), or fix or ' // &
        'drive that many nodal coordinates'
    else
      write(buf, '(a,i0,a)') '; the model is over-constrained (statically indeterminate): make ', &
        n_rows - this%n_c, ' dynamic modes elastic (calculable with stiffness), or ' // &
        'release modes, or free coordinates'
    end if
    msg = msg // trim(buf)
  end procedure model_count_message
end submodule model_system_finalize
