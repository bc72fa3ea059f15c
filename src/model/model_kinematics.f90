!> Kinematic analysis (docs/theory.md section 4): Newton solution of the calculable nodal
!> coordinates for given generalised coordinates q, then the first- and second-order
!> transfer functions DF and D2F from the one LU factorisation of the Jacobian at the solution.
module model_kinematics
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_NUMERIC, ERR_MODEL
  use core_linalg, only: lu_factor, lu_solve
  use model_system, only: model_t
  implicit none
  private
  public :: kinematics_t

  integer, parameter :: MAX_NEWTON = 25
  !> Pivots this much smaller than the largest mean a singular kinematic Jacobian.
  real(wp), parameter :: SINGULAR_PIVOT = 1.0e-12_wp

  type :: kinematics_t
    real(wp), allocatable :: x(:)        !< nodal coordinates at the last solution
    real(wp), allocatable :: q(:)        !< generalised coordinates of that solution
    real(wp), allocatable :: lu(:, :)    !< LU factors of the kinematic Jacobian at x
    !> d(residual)/d(q) through the nodal coordinates that are inputs, at x (n_c, n_q)
    real(wp), allocatable :: jac_in(:, :)
    integer, allocatable :: ipiv(:)
    real(wp), allocatable :: df(:, :)    !< DF_x (n_x, n_q); rows of fixed coordinates are 0
    logical :: has_df = .false.
    integer :: n_solves = 0, n_iterations = 0
  contains
    procedure :: init => kin_init
    procedure :: solve => kin_solve
    procedure :: transfer => kin_transfer
    procedure :: second => kin_second
    procedure :: residual => kin_residual
    procedure, private :: free_modes_moved => kin_free_modes_moved
  end type kinematics_t

contains

  subroutine kin_init(this, model)
    class(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    if (allocated(this%q)) deallocate(this%q, this%lu, this%ipiv, this%df, this%jac_in)
    this%x = model%x0
    allocate(this%q(model%n_q), this%lu(model%n_c, model%n_c), this%ipiv(model%n_c))
    allocate(this%jac_in(model%n_c, model%n_q))
    this%jac_in = 0.0_wp
    allocate(this%df(model%n_x, model%n_q))
    this%q = 0.0_wp
    this%df = 0.0_wp
    this%has_df = .false.
  end subroutine kin_init

  !> Residual r (n_c) of the kinematic equations at this%x and, if asked, their Jacobian with
  !> respect to the calculable coordinates and (jac_in) to q through the input coordinates.
  subroutine kin_residual(this, model, q, r, jac, jac_in)
    class(kinematics_t), intent(in) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:)
    real(wp), intent(out) :: r(:)
    real(wp), intent(out), optional :: jac(:, :), jac_in(:, :)
    real(wp), allocatable :: e(:), de(:, :)
    integer :: iel, j, k, row, col, nm
    r = 0.0_wp
    if (present(jac)) jac = 0.0_wp
    if (present(jac_in)) jac_in = 0.0_wp
    do iel = 1, model%n_elements
      associate (el => model%elements(iel)%e)
        nm = el%n_modes()
        allocate(e(nm), de(nm, size(el%dofs)))
        call el%evaluate(this%x(el%dofs), e, de)
        do j = 1, nm
          row = model%modes(model%mode_first(iel) + j - 1)%row
          if (row == 0) cycle
          r(row) = e(j)
          if (model%row_q(row) > 0) r(row) = e(j) - q(model%row_q(row))
          if (.not. present(jac)) cycle
          do k = 1, size(el%dofs)
            col = model%calc_index(el%dofs(k))
            if (col > 0) jac(row, col) = jac(row, col) + de(j, k)
            if (.not. present(jac_in)) cycle
            col = model%input_q(el%dofs(k))
            if (col > 0) jac_in(row, col) = jac_in(row, col) + de(j, k)
          end do
        end do
        deallocate(e, de)
      end associate
    end do
  end subroutine kin_residual

  !> Solve the kinematic equations for q, starting from the last solution moved along the
  !> first-order transfer function (a cheap predictor that keeps Newton on the right branch).
  !> On success the Jacobian at the solution is factorised and DF is NOT yet updated.
  subroutine kin_solve(this, model, q, err)
    class(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: q(:)
    type(error_t), intent(out) :: err
    real(wp) :: r(model%n_c), dx(model%n_c, 1), rmax, rcond, rprev
    real(wp) :: x_start(model%n_x)
    integer :: it, info, worst
    character(len=200) :: msg
    this%n_solves = this%n_solves + 1
    if (this%has_df) this%x = this%x + matmul(this%df, q - this%q)
    do it = 1, model%n_q
      if (model%q_coord(it) > 0) this%x(model%q_coord(it)) = model%x0(model%q_coord(it)) + q(it)
    end do
    x_start = this%x
    rprev = huge(1.0_wp)
    do it = 1, MAX_NEWTON
      call this%residual(model, q, r, this%lu, this%jac_in)
      rmax = 0.0_wp
      if (model%n_c > 0) rmax = maxval(abs(r))
      if (rmax /= rmax) exit
      call lu_factor(this%lu, this%ipiv, info, rcond, worst)
      if (info /= 0 .or. rcond < SINGULAR_PIVOT) then
        call err%set(ERR_MODEL, 'the kinematic Jacobian is singular: coordinate ' // &
          trim(model%coord_name(model%calc_coord(worst))) // ' is not determined by ' // &
          'the rigid, prescribed and dynamic modes (check the mode classes and supports; ' // &
          'elastic and released modes follow from the others and determine nothing)' // &
          this%free_modes_moved(model, worst))
        this%x = x_start
        return
      end if
      if (rmax <= model%newton_tol) then
        ! One more correction with these factors takes the error from rmax to about rmax^2:
        ! the stress of a stiff elastic mode is EA/l0 times its error, and statics
        ! differences such stresses.
        dx(:, 1) = -r
        call lu_solve(this%lu, this%ipiv, dx)
        this%x(model%calc_coord) = this%x(model%calc_coord) + dx(:, 1)
        this%q = q
        this%has_df = .false.
        this%n_iterations = this%n_iterations + it - 1
        return
      end if
      if (it > 3 .and. rmax > rprev) exit
      rprev = rmax
      dx(:, 1) = -r
      call lu_solve(this%lu, this%ipiv, dx)
      this%x(model%calc_coord) = this%x(model%calc_coord) + dx(:, 1)
    end do
    write(msg, '(a,i0,a,es10.3)') 'kinematic Newton iteration did not converge in ', it - 1, &
      ' iterations, residual ', rmax
    call err%set(ERR_NUMERIC, trim(msg))
    this%x = x_start
  end subroutine kin_solve

  !> The elastic and released modes that the undetermined motion changes. With the smallest
  !> pivot k of the factors J_c = P L U treated as zero, z_k = 1, z_(>k) = 0 and
  !> U(1:k-1, 1:k-1) z(1:k-1) = -U(1:k-1, k) solve U z = 0, so z is (nearly) the motion that
  !> nothing determines. A mode that changes along z is one whose promotion to dynamic or
  !> rigid would fix that motion. '' if none is found.
  function kin_free_modes_moved(this, model, k) result(hint)
    class(kinematics_t), intent(in) :: this
    type(model_t), intent(in) :: model
    integer, intent(in) :: k
    character(len=:), allocatable :: hint
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
  end function kin_free_modes_moved

  !> First-order transfer function DF_x = dx/dq at the last solution.
  subroutine kin_transfer(this, model)
    class(kinematics_t), intent(inout) :: this
    type(model_t), intent(in) :: model
    real(wp) :: b(model%n_c, model%n_q)
    integer :: row, iq
    b = -this%jac_in
    do row = 1, model%n_c
      if (model%row_q(row) > 0) b(row, model%row_q(row)) = 1.0_wp
    end do
    call lu_solve(this%lu, this%ipiv, b)
    this%df = 0.0_wp
    this%df(model%calc_coord, :) = b
    do iq = 1, model%n_q
      if (model%q_coord(iq) > 0) this%df(model%q_coord(iq), iq) = 1.0_wp
    end do
    this%has_df = .true.
  end subroutine kin_transfer

  !> Second-order transfer function contracted twice with qd: D2F_x qd qd (n_x).
  !> With x_dot = DF qd, J_c (D2F qd qd) = -D2D(x_dot, x_dot) over the kinematic rows.
  subroutine kin_second(this, model, qd, d2x)
    class(kinematics_t), intent(in) :: this
    type(model_t), intent(in) :: model
    real(wp), intent(in) :: qd(:)
    real(wp), intent(out) :: d2x(:)
    real(wp) :: xd(model%n_x), rhs(model%n_c, 1)
    real(wp), allocatable :: d2e(:)
    integer :: iel, j, row
    xd = matmul(this%df, qd)
    rhs = 0.0_wp
    do iel = 1, model%n_elements
      associate (el => model%elements(iel)%e)
        allocate(d2e(el%n_modes()))
        call el%second(this%x(el%dofs), xd(el%dofs), d2e)
        do j = 1, size(d2e)
          row = model%modes(model%mode_first(iel) + j - 1)%row
          if (row > 0) rhs(row, 1) = -d2e(j)
        end do
        deallocate(d2e)
      end associate
    end do
    call lu_solve(this%lu, this%ipiv, rhs)
    d2x = 0.0_wp
    d2x(model%calc_coord) = rhs(:, 1)
  end subroutine kin_second
end module model_kinematics
