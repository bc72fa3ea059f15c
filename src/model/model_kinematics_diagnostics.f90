!> The error path of the kinematics: why J_c is singular, naming the undetermined coordinate
!> and the modes whose class would fix it.
submodule (model_kinematics) model_kinematics_diagnostics
  implicit none

contains

  !> Why J_c is singular, from a dense factorisation (also in sparse mode: this is the error
  !> path, and the dense factors name the undetermined coordinate and the modes it moves).
  module procedure kin_singular_message
    type(kinematics_t) :: dense
    real(wp) :: r(model%n_c), rcond
    real(wp), allocatable :: jac(:, :)
    integer :: info, worst
    call dense%init(model, sparse=.false.)
    dense%x = this%x
    call dense%residual(model, q, r, jacobian=.true.)
    jac = dense%lu
    call lu_factor(dense%lu, dense%ipiv, info, rcond, worst)
    msg = 'the kinematic Jacobian is singular'
    if (units_only(jac)) then
      msg = msg // ' only in the units of the scene: its lengths and its rotations (rad) ' // &
        'differ by about 12 orders of magnitude or more (links of 1e12 length units or ' // &
        'longer), beyond what double precision tells from a singular matrix; give the ' // &
        'lengths in a larger unit'
      return
    end if
    if (worst < 1) return
    msg = msg // ': coordinate ' // trim(model%coord_name(model%calc_coord(worst))) // &
      ' is not determined by the rigid, prescribed and dynamic modes (check the mode ' // &
      'classes and supports; elastic and released modes follow from the others and ' // &
      'determine nothing)' // dense%free_modes_moved(model, worst)
  end procedure kin_singular_message

  !> Whether J is regular once its rows and columns are scaled to a largest entry of 1: its
  !> pivots then compare constraints and coordinates of one size, so that only units (a link
  !> of 3e12 m: rotations and translations 12 decades apart) made it look singular. A
  !> structurally singular J (a mode class that determines nothing, a dead point) stays so.
  logical function units_only(jac)
    real(wp), intent(inout) :: jac(:, :)
    real(wp) :: rcond, big
    integer :: ipiv(size(jac, 1)), info, i
    units_only = .false.
    if (size(jac, 1) == 0 .or. size(jac, 1) /= size(jac, 2)) return
    do i = 1, size(jac, 1)
      big = maxval(abs(jac(i, :)))
      if (.not. big > 0) return
      jac(i, :) = jac(i, :) / big
    end do
    do i = 1, size(jac, 2)
      big = maxval(abs(jac(:, i)))
      if (.not. big > 0) return
      jac(:, i) = jac(:, i) / big
    end do
    call lu_factor(jac, ipiv, info, rcond)
    units_only = info == 0 .and. rcond >= SINGULAR_PIVOT
  end function units_only

  module procedure kin_configuration_hint
    real(wp), parameter :: NEAR_SINGULAR = 1.0e3_wp
    real(wp) :: r(model%n_c), now
    integer :: info, worst
    character(len=9) :: growth
    hint = ''
    if (this%inv_norm_first <= 0 .or. model%n_c == 0 .or. .not. allocated(this%q)) return
    call this%residual(model, this%q, r, jacobian=.true.)
    call this%factor(info, worst)
    this%has_factors = info == 0
    this%has_df = .false.
    if (info == 0) then
      now = this%inverse_norm(model)
      if (.not. now > NEAR_SINGULAR * this%inv_norm_first) return
      write(growth, '(es9.2)') now / this%inv_norm_first
      hint = ' (the kinematic Jacobian is nearly singular there: ||J^-1|| ' // &
        trim(adjustl(growth)) // ' times that at the first solution'
    else
      hint = ' (the kinematic Jacobian is singular there'
    end if
    hint = hint // ': a singular configuration of the mechanism, e.g. links aligned at a ' // &
      'dead point)'
  end procedure kin_configuration_hint

  !> Power iteration on J^-T J^-1 from a fixed start, three rounds: near a singular
  !> configuration the smallest singular value stands far apart and it converges at once;
  !> elsewhere it is within a small factor, which the hint's 1e3 does not resolve.
  module procedure kin_inverse_norm
    real(wp) :: z(model%n_c, 1), zn
    integer :: round
    norm = 0.0_wp
    if (size(z, 1) == 0) return
    z = 1.0_wp / sqrt(real(size(z, 1), wp))
    do round = 1, 3
      call this%jacobian_solve(z)
      call this%jacobian_solve(z, transposed=.true.)
      zn = norm2(z)
      if (.not. zn > 0 .or. zn > huge(1.0_wp)) exit
      norm = sqrt(zn)
      z = z / zn
    end do
  end procedure kin_inverse_norm

  !> The elastic and released modes that the undetermined motion changes. With the smallest
  !> pivot k of the factors J_c = P L U treated as zero, z_k = 1, z_(>k) = 0 and
  !> U(1:k-1, 1:k-1) z(1:k-1) = -U(1:k-1, k) solve U z = 0, so z is (nearly) the motion that
  !> nothing determines. A mode that changes along z is one whose promotion to dynamic or
  !> rigid would fix that motion. '' if none is found.
  module procedure kin_free_modes_moved
    real(wp) :: z(model%n_c), dz(model%n_x)
    real(wp), allocatable :: e(:), de(:, :)
    integer :: iel, j, m, n_listed, i
    hint = ''
    if (model%n_c == 0) return
    z = 0.0_wp
    z(k) = 1.0_wp
    do i = k - 1, 1, -1
      if (this%lu(i, i) == 0) return
      z(i) = -(dot_product(this%lu(i, i + 1:k), z(i + 1:k))) / this%lu(i, i)
    end do
    dz = 0.0_wp
    dz(model%calc_coord) = z / maxval(abs(z))
    n_listed = 0
    do iel = 1, model%n_elements
      associate (el => model%elements(iel)%e)
        allocate(e(el%n_modes()), de(el%n_modes(), size(el%dofs)))
        call el%evaluate(this%x(el%dofs), e, de)
        do j = 1, el%n_modes()
          m = model%mode_first(iel) + j - 1
          if (model%modes(m)%row /= 0) cycle
          if (abs(dot_product(de(j, :), dz(el%dofs))) <= 1.0e-6_wp * &
              max(maxval(abs(de(j, :))), tiny(1.0_wp))) cycle
          n_listed = n_listed + 1
          if (n_listed > 4) cycle
          if (len(hint) > 0) hint = hint // ', '
          hint = hint // model%mode_name(m)
        end do
        deallocate(e, de)
      end associate
    end do
    if (n_listed > 4) hint = hint // ' and others'
    if (len(hint) > 0) hint = '; that motion changes ' // hint // ': make one of them ' // &
      'dynamic and another mode of the same loop elastic'
  end procedure kin_free_modes_moved
end submodule model_kinematics_diagnostics
